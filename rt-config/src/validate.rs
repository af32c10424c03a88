//! Semantic checks serde cannot express. Each problem names the key and what is wrong with it.

use crate::config::{CalibrationConfig, Config, ServiceRt};

#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    #[error("cannot read config {path}: {source}")]
    Read {
        path: String,
        source: std::io::Error,
    },
    #[error("config {origin}: {message}")]
    Parse { origin: String, message: String },
    #[error("config {origin}: {problem}")]
    Invalid { origin: String, problem: String },
}

pub(crate) fn validate(cfg: &Config) -> Result<(), String> {
    if cfg.uav.is_empty()
        || !cfg
            .uav
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
    {
        return Err(format!(
            "key `uav` = {:?}: must be non-empty and use only letters, digits, '-' and '_'",
            cfg.uav
        ));
    }
    if cfg.ipc_root.contains(char::is_whitespace) {
        return Err(format!(
            "key `ipc_root` = {:?}: must not contain whitespace",
            cfg.ipc_root
        ));
    }
    let s = &cfg.sensor;
    if !(s.bus.starts_with("/dev/") || s.bus.starts_with("sim:")) {
        return Err(format!(
            "key `sensor.bus` = {:?}: expected a Linux I2C device (/dev/i2c-N) or sim:<socket path>",
            s.bus
        ));
    }
    for (i, a) in s.addresses.iter().enumerate() {
        if !(0x68..=0x6F).contains(a) {
            return Err(format!(
                "key `sensor.addresses[{i}]` = 0x{a:02X}: an MCP3423 answers only on 0x68..=0x6F"
            ));
        }
        if s.addresses[..i].contains(a) {
            return Err(format!(
                "key `sensor.addresses[{i}]` = 0x{a:02X}: used twice; each cell needs its own chip"
            ));
        }
    }
    positive("sensor.rate_hz", s.rate_hz)?;
    if s.rate_hz > 240.0 * 1.3 {
        return Err(format!(
            "key `sensor.rate_hz` = {}: above what an MCP3423 delivers at 12 bits (<= 312 Hz)",
            s.rate_hz
        ));
    }
    if s.bus_retries > 10 {
        return Err(format!(
            "key `sensor.bus_retries` = {}: at most 10 fit in one period",
            s.bus_retries
        ));
    }
    positive("sensor.d0_m", s.d0_m)?;
    positive("sensor.h_m", s.h_m)?;
    positive("sensor.singularity_ratio", s.singularity_ratio)?;
    rotation("sensor.mounting_rotation", &s.mounting_rotation)?;
    let c = &s.cell;
    positive("sensor.cell.capacity_n", c.capacity_n)?;
    positive("sensor.cell.sensitivity_mv_per_v", c.sensitivity_mv_per_v)?;
    positive("sensor.cell.excitation_v", c.excitation_v)?;
    positive("sensor.cell.amplifier_gain", c.amplifier_gain)?;
    if !c.reference_v.is_finite() || !(0.0..=2.048).contains(&c.reference_v) {
        return Err(format!(
            "key `sensor.cell.reference_v` = {}: must lie in the ADC range 0..=2.048 V",
            c.reference_v
        ));
    }
    if cfg.filter.window == 0 || cfg.filter.window > 64 {
        return Err(format!(
            "key `filter.window` = {}: must be 1..=64 samples",
            cfg.filter.window
        ));
    }
    if let Some(cal) = &cfg.calibration {
        calibration(cal)?;
    }
    cfg.vehicle.validate()?;
    cfg.controller.validate()?;
    cfg.estimator.validate()?;
    cfg.mission.validate()?;
    cfg.px4.validate()?;
    cfg.recorder.validate()?;
    service("services.adc_sampler", &cfg.services.adc_sampler)?;
    service("services.tension", &cfg.services.tension)?;
    service("services.controller", &cfg.services.controller)?;
    service("services.px4_bridge", &cfg.services.px4_bridge)?;
    service("services.mission", &cfg.services.mission)?;
    service("services.force_estimator", &cfg.services.force_estimator)?;
    let sup = &cfg.supervisor;
    positive("supervisor.backoff_initial_s", sup.backoff_initial_s)?;
    positive("supervisor.backoff_max_s", sup.backoff_max_s)?;
    positive("supervisor.healthy_after_s", sup.healthy_after_s)?;
    if sup.backoff_max_s < sup.backoff_initial_s {
        return Err(format!(
            "key `supervisor.backoff_max_s` = {}: smaller than backoff_initial_s = {}",
            sup.backoff_max_s, sup.backoff_initial_s
        ));
    }
    Ok(())
}

fn positive(key: &str, v: f64) -> Result<(), String> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(format!("key `{key}` = {v}: must be a positive number"))
    }
}

fn finite(key: &str, values: &[f64]) -> Result<(), String> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(format!(
            "key `{key}[{i}]` = {}: not a finite number",
            values[i]
        )),
        None => Ok(()),
    }
}

fn rotation(key: &str, r: &[[f64; 3]; 3]) -> Result<(), String> {
    let flat: Vec<f64> = r.iter().flatten().copied().collect();
    finite(key, &flat)?;
    // R R^T = I and det R = +1, to 1e-6.
    for i in 0..3 {
        for j in 0..3 {
            let dot: f64 = (0..3).map(|k| r[i][k] * r[j][k]).sum();
            let want = if i == j { 1.0 } else { 0.0 };
            if (dot - want).abs() > 1e-6 {
                return Err(format!(
                    "key `{key}`: rows {i} and {j} are not orthonormal (dot = {dot:.6}); expected a rotation matrix"
                ));
            }
        }
    }
    let det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
        - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
        + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
    if (det - 1.0).abs() > 1e-6 {
        return Err(format!(
            "key `{key}`: determinant {det:.6}, expected +1 (a reflection is not a mounting)"
        ));
    }
    Ok(())
}

fn calibration(cal: &CalibrationConfig) -> Result<(), String> {
    for (i, g) in cal.cell_gain.iter().enumerate() {
        if !g.is_finite() || !(0.5..=2.0).contains(g) {
            return Err(format!(
                "key `calibration.cell_gain[{i}]` = {g}: a cell gain must lie in 0.5..=2.0"
            ));
        }
    }
    finite("calibration.poly_x", &cal.poly_x)?;
    finite("calibration.poly_y", &cal.poly_y)?;
    finite("calibration.poly_z", &cal.poly_z)?;
    for (axis, p) in [("x", &cal.poly_x), ("y", &cal.poly_y), ("z", &cal.poly_z)] {
        if !(0.5..=2.0).contains(&p[1]) {
            return Err(format!(
                "key `calibration.poly_{axis}[1]` = {}: the linear term must lie in 0.5..=2.0",
                p[1]
            ));
        }
    }
    let flat: Vec<f64> = cal.crossload.iter().flatten().copied().collect();
    finite("calibration.crossload", &flat)?;
    Ok(())
}

fn service(key: &str, s: &ServiceRt) -> Result<(), String> {
    if let Some(p) = s.priority {
        if !(1..=99).contains(&p) {
            return Err(format!(
                "key `{key}.priority` = {p}: SCHED_FIFO priorities are 1..=99"
            ));
        }
    }
    if let Some(core) = s.core {
        if core >= 1024 {
            return Err(format!("key `{key}.core` = {core}: not a CPU index"));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::Config;

    fn with(replace: &str, by: &str) -> Result<Config, String> {
        let text = crate::EMBEDDED_SIM_CONFIG.replacen(replace, by, 1);
        assert_ne!(
            text,
            crate::EMBEDDED_SIM_CONFIG,
            "pattern {replace:?} not found"
        );
        Config::from_toml_str(&text, "test.toml").map_err(|e| e.to_string())
    }

    #[test]
    fn embedded_config_is_valid() {
        let cfg = Config::embedded_sim();
        assert_eq!(cfg.uav, "uav1");
        assert_eq!(cfg.filter.window, 4);
        assert_eq!(cfg.sensor.addresses, [0x68, 0x6A, 0x6C, 0x6E]);
        assert!(cfg.calibration.is_some());
    }

    #[test]
    fn unknown_key_is_rejected_by_name() {
        let err = with("[filter]", "[filter]\nwindw = 3").unwrap_err();
        assert!(err.contains("windw"), "{err}");
        assert!(err.contains("test.toml"), "{err}");
    }

    #[test]
    fn bad_values_name_their_key() {
        let cases = [
            ("window = 4", "window = 0", "filter.window"),
            ("0x6E]", "0x20]", "sensor.addresses[3]"),
            ("0x6E]", "0x68]", "sensor.addresses[3]"),
            ("d0_m = 0.03", "d0_m = -1.0", "sensor.d0_m"),
            (
                "priority = 80",
                "priority = 120",
                "services.adc_sampler.priority",
            ),
            ("uav = \"uav1\"", "uav = \"uav 1\"", "uav"),
        ];
        for (from, to, key) in cases {
            let err = with(from, to).unwrap_err();
            assert!(err.contains(key), "{from} -> {to}: {err}");
        }
    }

    #[test]
    fn baseline_keys_parse_and_bad_ones_are_named() {
        let cfg = with("law = \"proposed\"", "law = \"geometric\"").unwrap();
        assert_eq!(cfg.controller.law, crate::ControllerLaw::Geometric);
        let cfg = with(
            "tension_source = \"sensor\"",
            "tension_source = \"estimator\"",
        )
        .unwrap();
        assert_eq!(
            cfg.controller.tension_source,
            crate::TensionSource::Estimator
        );
        let err = with("law = \"proposed\"", "law = \"lqr\"").unwrap_err();
        assert!(err.contains("law") && err.contains("lqr"), "{err}");
        let err = with("tension_source = \"sensor\"", "tension_source = \"gps\"").unwrap_err();
        assert!(
            err.contains("tension_source") && err.contains("gps"),
            "{err}"
        );
        let err = with("kp = [2.16, 2.16, 4.2]", "kp = [2.16, -1.0, 4.2]").unwrap_err();
        assert!(err.contains("controller.geometric.kp[1]"), "{err}");
        let err = with("\ncutoff_hz = 10.0", "\ncutoff_hz = -3.0").unwrap_err();
        assert!(err.contains("estimator.cutoff_hz"), "{err}");
    }

    #[test]
    fn wrong_type_is_reported_with_its_key() {
        let err = with("window = 4", "window = \"four\"").unwrap_err();
        assert!(err.contains("window"), "{err}");
    }

    #[test]
    fn reflection_is_not_a_mounting() {
        let err = with(
            "mounting_rotation = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]",
            "mounting_rotation = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]]",
        )
        .unwrap_err();
        assert!(err.contains("sensor.mounting_rotation"), "{err}");
    }

    #[test]
    fn effective_config_round_trips() {
        let cfg = Config::embedded_sim();
        let again = Config::from_toml_str(&cfg.to_toml(), "printed").unwrap();
        assert_eq!(cfg, again);
    }
}
