//! Loads a recording into memory: channels, metadata, attachments and typed samples.
//!
//! Reads front to back without the summary section, so a file cut short by a crash (no footer,
//! a torn last chunk) yields everything up to its last complete record; `truncated` says so.

use std::collections::BTreeMap;
use std::path::Path;

use mcap::read::{LinearReader, MessageStream, Options};
use mcap::records::Record;

use crate::format::{schema_name, Recordable, CHANNEL_TOPIC, CHANNEL_UAV};

/// One error enum for reading; each variant names the file or channel.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    #[error("cannot read {path}: {message}")]
    Io { path: String, message: String },
    #[error("{path} is not an MCAP file: {message}")]
    NotMcap { path: String, message: String },
    #[error("channel {topic} holds {found}, not {wanted}")]
    WrongSchema {
        topic: String,
        found: String,
        wanted: String,
    },
    #[error("message {index} on {topic} does not decode as {wanted}: {message}")]
    Decode {
        topic: String,
        index: usize,
        wanted: String,
        message: String,
    },
}

/// A sample and when the recorder took it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Timed<T> {
    /// MCAP `log_time`, ns.
    pub log_time_ns: u64,
    pub sample: T,
}

/// One channel of a recording and its messages, in file order.
#[derive(Debug, Clone, Default)]
pub struct ChannelData {
    pub topic: String,
    pub schema_name: String,
    pub metadata: BTreeMap<String, String>,
    /// (log_time ns, JSON bytes).
    pub messages: Vec<(u64, Vec<u8>)>,
}

/// A whole recording in memory.
#[derive(Debug, Clone, Default)]
pub struct Recording {
    pub channels: Vec<ChannelData>,
    /// Metadata records by name (the last one wins if a name repeats).
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
    /// Attachments by name.
    pub attachments: BTreeMap<String, Vec<u8>>,
    /// The file ended before its footer, or a record was torn: read up to the last good one.
    pub truncated: bool,
}

impl Recording {
    pub fn open(path: &Path) -> Result<Self, ReadError> {
        let p = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|e| ReadError::Io {
            path: p.clone(),
            message: e.to_string(),
        })?;
        Self::from_bytes(&bytes).map_err(|message| ReadError::NotMcap { path: p, message })
    }

    /// Parses a recording held in memory; `Err` only if not even the header is MCAP.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, String> {
        if !bytes.starts_with(mcap::MAGIC) {
            return Err("no MCAP magic at the start".into());
        }
        let mut rec = Recording::default();
        // Pass 1: metadata and attachments (outside chunks).
        let records = LinearReader::new_with_options(bytes, Options::IgnoreEndMagic.into())
            .map_err(|e| e.to_string())?;
        let mut saw_footer = false;
        for r in records {
            match r {
                Ok(Record::Metadata(m)) => {
                    rec.metadata.insert(m.name, m.metadata);
                }
                Ok(Record::Attachment { header, data, .. }) => {
                    rec.attachments.insert(header.name, data.into_owned());
                }
                Ok(Record::Footer(_)) => saw_footer = true,
                Ok(_) => {}
                Err(_) => {
                    rec.truncated = true;
                    break;
                }
            }
        }
        rec.truncated |= !saw_footer;
        // Pass 2: messages, chunks decompressed.
        let mut index: BTreeMap<u16, usize> = BTreeMap::new();
        let stream = MessageStream::new_with_options(bytes, Options::IgnoreEndMagic.into())
            .map_err(|e| e.to_string())?;
        for m in stream {
            let Ok(m) = m else {
                rec.truncated = true;
                break;
            };
            let i = *index.entry(m.channel.id).or_insert_with(|| {
                rec.channels.push(ChannelData {
                    topic: m.channel.topic.clone(),
                    schema_name: m
                        .channel
                        .schema
                        .as_ref()
                        .map(|s| s.name.clone())
                        .unwrap_or_default(),
                    metadata: m.channel.metadata.clone(),
                    messages: Vec::new(),
                });
                rec.channels.len() - 1
            });
            rec.channels[i]
                .messages
                .push((m.log_time, m.data.into_owned()));
        }
        Ok(rec)
    }

    /// The channel of `topic` (`/<uav>/<topic>`), if it has messages.
    pub fn channel(&self, topic: &str) -> Option<&ChannelData> {
        self.channels.iter().find(|c| c.topic == topic)
    }

    /// Drone ids with at least one channel, in order of appearance (the plant excluded).
    pub fn uavs(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for c in &self.channels {
            if let Some(u) = c.metadata.get(CHANNEL_UAV) {
                if u != shared_types::names::PLANT && !out.contains(u) {
                    out.push(u.clone());
                }
            }
        }
        out
    }

    /// Every sample of `uav`'s `topic` decoded as `T`, in file order (empty if none recorded).
    pub fn samples<T: Recordable>(
        &self,
        uav: &str,
        topic: &str,
    ) -> Result<Vec<Timed<T>>, ReadError> {
        let name = crate::channel_topic(uav, topic);
        let Some(ch) = self.channel(&name) else {
            return Ok(Vec::new());
        };
        let wanted = schema_name::<T>();
        if ch.schema_name != wanted {
            return Err(ReadError::WrongSchema {
                topic: name,
                found: ch.schema_name.clone(),
                wanted,
            });
        }
        ch.messages
            .iter()
            .enumerate()
            .map(|(index, (t, data))| {
                serde_json::from_slice(data)
                    .map(|sample| Timed {
                        log_time_ns: *t,
                        sample,
                    })
                    .map_err(|e| ReadError::Decode {
                        topic: name.clone(),
                        index,
                        wanted: wanted.clone(),
                        message: e.to_string(),
                    })
            })
            .collect()
    }

    /// A metadata value, if present.
    pub fn meta(&self, record: &str, key: &str) -> Option<&str> {
        self.metadata.get(record)?.get(key).map(String::as_str)
    }

    /// The `topic` channel metadata of a channel (its taut topic name).
    pub fn taut_topic(ch: &ChannelData) -> Option<&str> {
        ch.metadata.get(CHANNEL_TOPIC).map(String::as_str)
    }
}
