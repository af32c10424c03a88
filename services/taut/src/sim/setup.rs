//! What a simulated flight needs around the services: a run id, free loopback ports, and one
//! config per drone derived from the embedded simulation config (no file from the user).

use rt_config::{Config, OnDeath};
use sim_plant::scenario::Scenario;
use std::net::{TcpListener, UdpSocket};
use std::path::{Path, PathBuf};

/// The emulated sensor's calibration (see the file's header).
pub const SIM_CALIBRATION: &str = include_str!("../../../../configs/sim-calibration.toml");

/// Loopback ports of one run: MAVLink (companion side 14540-like, plant side 14580-like, each
/// +i per drone) and one zenoh listener per drone.
#[derive(Debug, Clone, Copy)]
pub struct Ports {
    pub mavlink_remote_base: u16,
    pub mavlink_local_base: u16,
    pub zenoh: [u16; 2],
}

/// Two consecutive free UDP ports, probed by binding (a race with other programs is possible
/// but short: the plant and the bridges bind them a moment later).
fn free_udp_pair(avoid: &[u16]) -> Result<u16, String> {
    let seed = std::process::id() as u32;
    for attempt in 0..200u32 {
        let base = 20_000 + ((seed.wrapping_mul(7919) + attempt * 104_729) % 40_000) as u16;
        if avoid.contains(&base) || avoid.contains(&(base + 1)) {
            continue;
        }
        let a = UdpSocket::bind(("127.0.0.1", base));
        let b = UdpSocket::bind(("127.0.0.1", base + 1));
        if a.is_ok() && b.is_ok() {
            return Ok(base);
        }
    }
    Err("no two consecutive free UDP ports on 127.0.0.1".into())
}

fn free_tcp() -> Result<u16, String> {
    let l = TcpListener::bind(("127.0.0.1", 0)).map_err(|e| format!("no free TCP port: {e}"))?;
    l.local_addr()
        .map(|a| a.port())
        .map_err(|e| format!("no free TCP port: {e}"))
}

impl Ports {
    pub fn pick() -> Result<Ports, String> {
        let remote = free_udp_pair(&[])?;
        let local = free_udp_pair(&[remote, remote + 1])?;
        let z0 = free_tcp()?;
        let mut z1 = free_tcp()?;
        while z1 == z0 {
            z1 = free_tcp()?;
        }
        Ok(Ports {
            mavlink_remote_base: remote,
            mavlink_local_base: local,
            zenoh: [z0, z1],
        })
    }
}

/// The config of drone `k` of `scenario` for this run.
pub fn drone_config(
    scenario_arg: &str,
    scenario: &Scenario,
    k: usize,
    ipc_root: &str,
    socket_dir: &Path,
    ports: &Ports,
) -> Config {
    let mut cfg = Config::embedded_sim();
    cfg.calibration = Some(sim_calibration());
    let id = scenario.drones[k].id.clone();
    let peer = scenario.drones[1 - k].id.clone();
    cfg.uav = id.clone();
    cfg.ipc_root = ipc_root.to_string();
    cfg.sensor.bus = format!(
        "sim:{}",
        socket_dir.join(format!("taut-{id}-i2c.sock")).display()
    );
    cfg.px4.link = format!("udpin:127.0.0.1:{}", ports.mavlink_remote_base + k as u16);
    cfg.px4.target_system = k as u8 + 1;
    cfg.mission.scenario = scenario_arg.to_string();
    cfg.mission.drone = id;
    cfg.mission.peer = peer;
    cfg.mission.listen = vec![format!("tcp/127.0.0.1:{}", ports.zenoh[k])];
    cfg.mission.connect = vec![format!("tcp/127.0.0.1:{}", ports.zenoh[1 - k])];
    // A simulated flight is judged as a whole: a dying service ends it.
    cfg.supervisor.on_death = OnDeath::StopAll;
    cfg
}

/// Writes each drone's config to `<out>/config/<id>.toml` and returns the paths.
pub fn write_configs(out: &Path, cfgs: &[Config; 2]) -> Result<[PathBuf; 2], String> {
    let dir = out.join("config");
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let write = |c: &Config| {
        let p = dir.join(format!("{}.toml", c.uav));
        std::fs::write(&p, c.to_toml()).map_err(|e| format!("{}: {e}", p.display()))?;
        Ok::<_, String>(p)
    };
    Ok([write(&cfgs[0])?, write(&cfgs[1])?])
}

/// A scenario argument the child processes can open from any directory: embedded names stay,
/// a file becomes absolute.
pub fn scenario_arg_for_children(arg: &str) -> String {
    let p = Path::new(arg);
    if p.exists() {
        std::fs::canonicalize(p)
            .map(|a| a.display().to_string())
            .unwrap_or_else(|_| arg.to_string())
    } else {
        arg.to_string()
    }
}

/// The `[calibration]` table of [`SIM_CALIBRATION`].
pub fn sim_calibration() -> rt_config::CalibrationConfig {
    #[derive(serde::Deserialize)]
    struct File {
        calibration: rt_config::CalibrationConfig,
    }
    toml::from_str::<File>(SIM_CALIBRATION)
        .expect("configs/sim-calibration.toml is checked by a unit test")
        .calibration
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_sim_calibration_parses_and_is_not_identity() {
        let c = super::sim_calibration();
        assert_ne!(c, rt_config::CalibrationConfig::identity());
        assert!(c.cell_gain.iter().all(|g| (g - 1.0).abs() < 0.05));
    }
}
