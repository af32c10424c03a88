//! `taut record`: the recorder service for several drones at once (simulation: both drones and
//! the plant's truth in one file). On a drone, `taut launch` runs `taut svc recorder` instead.

use clap::Args;
use recorder::shell::{record, RecordOptions};
use std::path::PathBuf;

#[derive(Args, Debug, Clone)]
pub struct RecordArgs {
    /// The MCAP file to write (replaced if it exists).
    #[arg(long)]
    pub out: PathBuf,
    /// iceoryx2 root of the services (a config's `ipc_root`).
    #[arg(long, default_value = "")]
    pub root: String,
    /// A drone id to record; repeatable.
    #[arg(long = "uav", required = true)]
    pub uavs: Vec<String>,
    /// Also record the plant's ground truth.
    #[arg(long)]
    pub truth: bool,
    /// `UAV=FILE`: attach FILE as drone UAV's configuration; repeatable.
    #[arg(long = "attach")]
    pub attach: Vec<String>,
    /// Close a chunk once it spans this long (the most a SIGKILL loses), s.
    #[arg(long, default_value_t = 1.0)]
    pub chunk_period_s: f64,
    /// Samples each subscriber holds before the oldest are lost.
    #[arg(long, default_value_t = taut_ipc::SUBSCRIBER_MAX_BUFFER)]
    pub buffer: usize,
    /// Create this file once subscribed to every topic.
    #[arg(long)]
    pub ready: Option<PathBuf>,
}

impl RecordArgs {
    /// Checks the arguments and reads the attachments.
    pub fn options(&self) -> Result<RecordOptions, String> {
        if !(self.chunk_period_s.is_finite() && (0.01..=60.0).contains(&self.chunk_period_s)) {
            return Err(format!(
                "--chunk-period-s {}: must lie in 0.01..=60",
                self.chunk_period_s
            ));
        }
        if !(1..=taut_ipc::SUBSCRIBER_MAX_BUFFER).contains(&self.buffer) {
            return Err(format!(
                "--buffer {}: must be 1..={}",
                self.buffer,
                taut_ipc::SUBSCRIBER_MAX_BUFFER
            ));
        }
        let mut configs = Vec::new();
        for a in &self.attach {
            let (uav, path) = a
                .split_once('=')
                .ok_or_else(|| format!("--attach {a:?}: expected UAV=FILE"))?;
            if !self.uavs.iter().any(|u| u == uav) {
                return Err(format!("--attach {a:?}: {uav} is not a recorded --uav"));
            }
            let text = std::fs::read_to_string(path).map_err(|e| format!("--attach {a:?}: {e}"))?;
            configs.push((uav.to_string(), text));
        }
        Ok(RecordOptions {
            ipc_root: self.root.clone(),
            uavs: self.uavs.clone(),
            truth: self.truth,
            out: self.out.clone(),
            configs,
            chunk_period_ns: (self.chunk_period_s * 1e9) as u64,
            buffer: self.buffer,
            ready_file: self.ready.clone(),
            node_name: format!("recorder-{}", std::process::id()),
        })
    }
}

pub fn run(args: &RecordArgs) -> Result<(), String> {
    let opts = args.options()?;
    taut_ipc::install_stop_handler();
    record(&opts).map(drop)
}
