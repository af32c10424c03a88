//! Writes a recording in the layout of [`crate::format`]: the recorder service uses it, and fast
//! mode in-process (it knows nothing of iceoryx2). Off the real-time path, but cheap: one JSON
//! buffer reused for every message, zstd on the writing thread.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Seek, Write};
use std::path::Path;

use mcap::records::{MessageHeader, Metadata};
use mcap::{Attachment, WriteOptions, Writer};

use crate::format::{
    channel_topic, config_attachment, schema_json, schema_name, Recordable, CHANNEL_TOPIC,
    CHANNEL_TYPE, CHANNEL_UAV, CONFIG_MEDIA_TYPE, MESSAGE_ENCODING, META_RECORDING,
    SCHEMA_ENCODING,
};
pub use crate::stats::ChannelStats;

/// The default chunk period: at most this much log time is lost to a SIGKILL, ns.
pub const DEFAULT_CHUNK_PERIOD_NS: u64 = 1_000_000_000;

/// How the samples were timed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Services in real time; log time is CLOCK_MONOTONIC.
    Realtime,
    /// `taut sim --fast`; log time is simulated.
    Fast,
}

impl Mode {
    pub fn as_str(self) -> &'static str {
        match self {
            Mode::Realtime => "realtime",
            Mode::Fast => "fast",
        }
    }
    fn clock(self) -> &'static str {
        match self {
            Mode::Realtime => "CLOCK_MONOTONIC",
            Mode::Fast => "simulated",
        }
    }
}

/// What the `taut.recording` metadata says.
#[derive(Debug, Clone)]
pub struct RecordingInfo {
    pub mode: Mode,
    /// Drone ids recorded (the plant not included).
    pub uavs: Vec<String>,
    /// Close the open chunk once it spans this much log time, ns (> 0).
    pub chunk_period_ns: u64,
}

impl RecordingInfo {
    pub fn new(mode: Mode, uavs: Vec<String>) -> Self {
        Self {
            mode,
            uavs,
            chunk_period_ns: DEFAULT_CHUNK_PERIOD_NS,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum CreateError {
    #[error("cannot create recording {path}: {message}")]
    Io { path: String, message: String },
    #[error("cannot start recording {path}: {message}")]
    Mcap { path: String, message: String },
    #[error("chunk period must be > 0 ns")]
    ChunkPeriod,
}

#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    #[error("writing {topic}: {message}")]
    Mcap { topic: String, message: String },
    #[error("{topic} carries {channel_type}, not {given}")]
    WrongType {
        topic: String,
        channel_type: &'static str,
        given: &'static str,
    },
    #[error("no channel {index} in this recording")]
    NoChannel { index: usize },
    #[error("{topic}: a sample does not encode as JSON: {message}")]
    Encode { topic: String, message: String },
}

/// A channel added with [`RecordingWriter::add_channel`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ChannelHandle {
    index: usize,
    type_name: &'static str,
}

struct ChannelState {
    id: u16,
    stats: ChannelStats,
}

/// An MCAP recording being written.
pub struct RecordingWriter<W: Write + Seek = BufWriter<File>> {
    mcap: Writer<W>,
    channels: Vec<ChannelState>,
    json: Vec<u8>,
    chunk_period_ns: u64,
    /// Log time of the first message in the open chunk.
    chunk_opened_ns: Option<u64>,
}

impl RecordingWriter<BufWriter<File>> {
    /// Creates (truncates) `path` and writes the header and `taut.recording`.
    pub fn create(path: &Path, info: &RecordingInfo) -> Result<Self, CreateError> {
        let p = path.display().to_string();
        let file = File::create(path).map_err(|e| CreateError::Io {
            path: p.clone(),
            message: e.to_string(),
        })?;
        Self::from_writer(BufWriter::with_capacity(1 << 16, file), info).map_err(|e| match e {
            CreateError::Mcap { message, .. } => CreateError::Mcap { path: p, message },
            other => other,
        })
    }
}

impl<W: Write + Seek> RecordingWriter<W> {
    /// Starts a recording on any seekable writer (a `Cursor<Vec<u8>>` in tests).
    pub fn from_writer(w: W, info: &RecordingInfo) -> Result<Self, CreateError> {
        if info.chunk_period_ns == 0 {
            return Err(CreateError::ChunkPeriod);
        }
        let mcap_err = |e: mcap::McapError| CreateError::Mcap {
            path: "<writer>".into(),
            message: e.to_string(),
        };
        let options = WriteOptions::new()
            .profile("taut")
            // Compress on this thread: the machine has two cores and the services come first.
            .compression_threads(0);
        let mut mcap = options.create(w).map_err(mcap_err)?;
        let metadata = BTreeMap::from([
            ("clock".to_string(), info.mode.clock().to_string()),
            ("mode".to_string(), info.mode.as_str().to_string()),
            ("uavs".to_string(), info.uavs.join(",")),
            (
                "chunk_period_ns".to_string(),
                info.chunk_period_ns.to_string(),
            ),
            ("taut_version".to_string(), env!("CARGO_PKG_VERSION").into()),
        ]);
        mcap.write_metadata(&Metadata {
            name: META_RECORDING.to_string(),
            metadata,
        })
        .map_err(mcap_err)?;
        mcap.flush().map_err(mcap_err)?;
        Ok(Self {
            mcap,
            channels: Vec::new(),
            json: Vec::with_capacity(4096),
            chunk_period_ns: info.chunk_period_ns,
            chunk_opened_ns: None,
        })
    }

    /// Adds the channel `/<uav>/<topic>` carrying `T` (its schema once per type).
    pub fn add_channel<T: Recordable>(
        &mut self,
        uav: &str,
        topic: &str,
    ) -> Result<ChannelHandle, WriteError> {
        let name = channel_topic(uav, topic);
        let err = |e: mcap::McapError| WriteError::Mcap {
            topic: name.clone(),
            message: e.to_string(),
        };
        // The writer deduplicates identical schema records.
        let schema_id = self
            .mcap
            .add_schema(&schema_name::<T>(), SCHEMA_ENCODING, &schema_json::<T>())
            .map_err(err)?;
        let metadata = BTreeMap::from([
            (CHANNEL_UAV.to_string(), uav.to_string()),
            (CHANNEL_TOPIC.to_string(), topic.to_string()),
            (CHANNEL_TYPE.to_string(), T::TYPE_NAME.to_string()),
        ]);
        let id = self
            .mcap
            .add_channel(schema_id, &name, MESSAGE_ENCODING, &metadata)
            .map_err(err)?;
        self.channels.push(ChannelState {
            id,
            stats: ChannelStats::new(name),
        });
        Ok(ChannelHandle {
            index: self.channels.len() - 1,
            type_name: T::TYPE_NAME,
        })
    }

    /// Attaches `uav`'s effective configuration (TOML) and flushes it to the OS at once.
    pub fn attach_config(&mut self, uav: &str, toml_text: &str) -> Result<(), WriteError> {
        let name = config_attachment(uav);
        let err = |e: mcap::McapError| WriteError::Mcap {
            topic: name.clone(),
            message: e.to_string(),
        };
        self.mcap
            .attach(&Attachment {
                log_time: 0,
                create_time: 0,
                name: name.clone(),
                media_type: CONFIG_MEDIA_TYPE.to_string(),
                data: toml_text.as_bytes().into(),
            })
            .map_err(err)?;
        self.mcap.flush().map_err(err)?;
        self.chunk_opened_ns = None;
        Ok(())
    }

    /// Writes one sample taken at `log_time_ns`, accounts its sequence, and closes the chunk
    /// if it now spans the chunk period.
    pub fn write<T: Recordable>(
        &mut self,
        ch: ChannelHandle,
        log_time_ns: u64,
        sample: &T,
    ) -> Result<(), WriteError> {
        let state = self
            .channels
            .get_mut(ch.index)
            .ok_or(WriteError::NoChannel { index: ch.index })?;
        if ch.type_name != T::TYPE_NAME {
            return Err(WriteError::WrongType {
                topic: state.stats.topic.clone(),
                channel_type: ch.type_name,
                given: T::TYPE_NAME,
            });
        }
        self.json.clear();
        serde_json::to_writer(&mut self.json, sample).map_err(|e| WriteError::Encode {
            topic: state.stats.topic.clone(),
            message: e.to_string(),
        })?;
        let h = sample.header();
        let header = MessageHeader {
            channel_id: state.id,
            sequence: h.sequence as u32,
            log_time: log_time_ns,
            publish_time: h.t_publish_ns,
        };
        self.mcap
            .write_to_known_channel(&header, &self.json)
            .map_err(|e| WriteError::Mcap {
                topic: state.stats.topic.clone(),
                message: e.to_string(),
            })?;
        state.stats.observe(h.sequence);
        self.chunk_opened_ns.get_or_insert(log_time_ns);
        self.tick(log_time_ns)?;
        Ok(())
    }

    /// Closes the open chunk (and flushes it to the OS) if it is a chunk period old at
    /// `now_ns`. Returns whether it did. Call it when idle too, so a quiet stream is not held
    /// back in memory.
    pub fn tick(&mut self, now_ns: u64) -> Result<bool, WriteError> {
        match self.chunk_opened_ns {
            Some(t0) if now_ns.saturating_sub(t0) >= self.chunk_period_ns => {
                self.flush()?;
                Ok(true)
            }
            _ => Ok(false),
        }
    }

    /// Closes the open chunk and flushes everything to the OS.
    pub fn flush(&mut self) -> Result<(), WriteError> {
        self.chunk_opened_ns = None;
        self.mcap.flush().map_err(|e| WriteError::Mcap {
            topic: "<chunk>".into(),
            message: e.to_string(),
        })
    }

    /// What each channel took and lost so far, in the order channels were added.
    pub fn stats(&self) -> Vec<ChannelStats> {
        self.channels.iter().map(|c| c.stats.clone()).collect()
    }

    /// Writes the close metadata (drops, received, sequences) and the summary, and flushes
    /// the file. Returns the per-channel stats.
    pub fn finish(self) -> Result<Vec<ChannelStats>, WriteError> {
        self.finish_into_inner().map(|(stats, _)| stats)
    }

    /// [`Self::finish`], handing back the underlying writer too.
    pub fn finish_into_inner(mut self) -> Result<(Vec<ChannelStats>, W), WriteError> {
        let stats = self.stats();
        let err = |message: String| WriteError::Mcap {
            topic: "<summary>".into(),
            message,
        };
        for (name, metadata) in crate::stats::close_metadata(&stats) {
            self.mcap
                .write_metadata(&Metadata {
                    name: name.to_string(),
                    metadata,
                })
                .map_err(|e| err(e.to_string()))?;
        }
        self.mcap.finish().map_err(|e| err(e.to_string()))?;
        let mut w = self.mcap.into_inner();
        w.flush().map_err(|e| err(e.to_string()))?;
        Ok((stats, w))
    }
}

#[cfg(test)]
#[path = "write_tests.rs"]
mod tests;
