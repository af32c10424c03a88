//! `taut calibrate`: placeholder until the calibration library lands.
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct CalibrateArgs {
    #[arg(long)]
    pub out: PathBuf,
}

pub fn run(_args: &CalibrateArgs) -> Result<(), String> {
    Err("not wired yet".into())
}
