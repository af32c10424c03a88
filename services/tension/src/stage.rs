//! The per-sample tension step.

use crate::{calibration::mat3_mul, cells, Calibration, CellConversion, Geometry, MovingAverage};
use rt_config::Config;
use shared_types::{tension_flags as flag, ChannelStatus, Header, RawAdcFrame, TensionSample};

/// Everything the stage needs from the config, resolved once at start.
#[derive(Debug, Clone)]
pub struct TensionStageConfig {
    pub conversion: CellConversion,
    pub calibration: Calibration,
    pub geometry: Geometry,
    /// Sensor frame S to body FRD, row-major.
    pub mounting_rotation: [[f64; 3]; 3],
    pub window: usize,
    pub singularity_ratio: f64,
}

impl TensionStageConfig {
    pub fn from_config(cfg: &Config) -> Self {
        Self {
            conversion: CellConversion::new(&cfg.sensor.cell),
            calibration: Calibration::new(cfg.calibration.as_ref()),
            geometry: Geometry {
                d0_m: cfg.sensor.d0_m,
                h_m: cfg.sensor.h_m,
            },
            mounting_rotation: cfg.sensor.mounting_rotation,
            window: cfg.filter.window,
            singularity_ratio: cfg.sensor.singularity_ratio,
        }
    }
}

/// Lateral pull below which the singularity test is not meaningful (noise at no load), N.
const SINGULARITY_MIN_LATERAL_N: f64 = 0.5;

/// RawAdcFrame in, TensionSample out; state is the filter and the last good output.
#[derive(Debug, Clone)]
pub struct TensionStage {
    cfg: TensionStageConfig,
    filter: MovingAverage<4>,
    /// Newest `t_origin_ns` in the window is the input's; kept for the output header.
    sequence: u64,
    last_raw_sequence: Option<u64>,
    last_good: TensionSample,
}

impl TensionStage {
    pub fn new(cfg: TensionStageConfig) -> Self {
        Self {
            filter: MovingAverage::new(cfg.window),
            cfg,
            sequence: 0,
            last_raw_sequence: None,
            last_good: TensionSample::default(),
        }
    }

    pub fn config(&self) -> &TensionStageConfig {
        &self.cfg
    }

    /// One step. `t_publish_ns` is left 0: the shell stamps it when it publishes.
    pub fn process(&mut self, frame: &RawAdcFrame) -> TensionSample {
        let mut flags = 0;
        if self.cfg.calibration.is_missing() {
            flags |= flag::CALIBRATION_MISSING;
        }
        for (status, code) in frame.status.iter().zip(frame.codes) {
            match status {
                ChannelStatus::Fresh if cells::is_saturated(code) => flags |= flag::SATURATED,
                ChannelStatus::Fresh => {}
                ChannelStatus::Saturated => flags |= flag::SATURATED,
                ChannelStatus::Stale | ChannelStatus::BusError => flags |= flag::STALE_INPUT,
            }
        }
        if let Some(last) = self.last_raw_sequence {
            if frame.header.sequence != last.wrapping_add(1) {
                flags |= flag::INPUT_GAP;
            }
        }
        self.last_raw_sequence = Some(frame.header.sequence);

        let raw = self.cfg.conversion.forces_from_codes(&frame.codes);
        let cells = self.filter.push(self.cfg.calibration.correct_cells(&raw));
        if !self.filter.is_full() {
            flags |= flag::FILTER_WARMUP;
        }
        let t_eq = self.cfg.geometry.force_from_cells(&cells);
        let t_s = self.cfg.calibration.correct_force(&t_eq);
        let t_b = mat3_mul(&self.cfg.mounting_rotation, &t_s);

        let lateral = t_s[0].hypot(t_s[1]);
        if lateral > SINGULARITY_MIN_LATERAL_N
            && t_s[2].abs() < self.cfg.singularity_ratio * lateral
        {
            flags |= flag::NEAR_SINGULARITY;
        }

        let header = Header {
            sequence: self.sequence,
            t_origin_ns: frame.header.t_origin_ns,
            t_publish_ns: 0,
        };
        self.sequence += 1;
        let finite = cells.iter().chain(&t_s).chain(&t_b).all(|v| v.is_finite());
        if !finite {
            // Hold the last finite force rather than pass a NaN to the controller.
            return TensionSample {
                header,
                flags: flags | flag::NON_FINITE,
                raw_sequence: frame.header.sequence,
                ..self.last_good
            };
        }
        let out = TensionSample {
            header,
            cell_force_n: cells,
            force_sensor_n: t_s,
            force_body_n: t_b,
            flags,
            raw_sequence: frame.header.sequence,
        };
        self.last_good = out;
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rt_config::CellConfig;

    fn stage(
        window: usize,
        rotation: [[f64; 3]; 3],
        cal: Option<&rt_config::CalibrationConfig>,
    ) -> TensionStage {
        TensionStage::new(TensionStageConfig {
            conversion: CellConversion::new(&CellConfig::default()),
            calibration: Calibration::new(cal),
            geometry: Geometry {
                d0_m: 0.03,
                h_m: 0.03,
            },
            mounting_rotation: rotation,
            window,
            singularity_ratio: 0.25,
        })
    }

    fn frame(seq: u64, codes: [i16; 4]) -> RawAdcFrame {
        RawAdcFrame {
            header: Header {
                sequence: seq,
                t_origin_ns: 1000 + seq,
                t_publish_ns: 0,
            },
            codes,
            ..RawAdcFrame::default()
        }
    }

    const ID: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    /// 16.3155 mV/N: a code step of 1 LSB is 0.0613 N per cell.
    const MV_PER_N: f64 = 800.0 / 49.03325;

    #[test]
    fn hanging_load_by_hand() {
        // 40 N hanging: 10 N per cell, 163.155 mV over the 500 mV reference -> code 663.
        let mut s = stage(1, ID, Some(&rt_config::CalibrationConfig::identity()));
        let out = s.process(&frame(0, [663; 4]));
        let expect = 4.0 * 163.0 / MV_PER_N; // what code 663 means exactly
        assert!((out.force_sensor_n[2] - expect).abs() < 1e-9);
        assert!(out.force_sensor_n[0].abs() < 1e-12 && out.force_sensor_n[1].abs() < 1e-12);
        assert_eq!(out.force_body_n, out.force_sensor_n);
        assert_eq!(out.flags, 0);
        assert_eq!(out.header.t_origin_ns, 1000);
    }

    #[test]
    fn lateral_pull_by_hand() {
        // Cell 1 pulled 100 mV more than cell 3: T_x = -(d0/h)(f1 - f3) = +100/MV_PER_N... with
        // f1 - f3 = -(100 mV)/MV_PER_N, so T_x = +6.129 N forward.
        let mut s = stage(1, ID, Some(&rt_config::CalibrationConfig::identity()));
        let out = s.process(&frame(0, [650, 600, 550, 600]));
        assert!((out.force_sensor_n[0] - 100.0 / MV_PER_N).abs() < 1e-9);
        assert!(out.force_sensor_n[1].abs() < 1e-12);
        assert!((out.force_sensor_n[2] - 4.0 * 100.0 / MV_PER_N).abs() < 1e-9);
    }

    #[test]
    fn mounting_rotation_maps_sensor_to_body() {
        // Sensor yawed 90 degrees: S x is body y.
        let yaw90 = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
        let mut s = stage(1, yaw90, Some(&rt_config::CalibrationConfig::identity()));
        let out = s.process(&frame(0, [650, 600, 550, 600]));
        assert!(out.force_body_n[0].abs() < 1e-12);
        assert!((out.force_body_n[1] - out.force_sensor_n[0]).abs() < 1e-12);
    }

    #[test]
    fn filter_averages_and_flags_warmup() {
        let mut s = stage(4, ID, Some(&rt_config::CalibrationConfig::identity()));
        let a = s.process(&frame(0, [500; 4]));
        assert_ne!(a.flags & flag::FILTER_WARMUP, 0);
        s.process(&frame(1, [500; 4]));
        s.process(&frame(2, [500; 4]));
        let d = s.process(&frame(3, [900; 4]));
        assert_eq!(d.flags & flag::FILTER_WARMUP, 0);
        assert!((d.force_sensor_n[2] - 4.0 * 100.0 / MV_PER_N).abs() < 1e-9);
    }

    #[test]
    fn flags_for_bad_inputs() {
        let mut s = stage(1, ID, None);
        let mut f = frame(0, [2047, 600, 600, 600]);
        f.status[1] = ChannelStatus::Stale;
        let out = s.process(&f);
        assert_ne!(out.flags & flag::SATURATED, 0);
        assert_ne!(out.flags & flag::STALE_INPUT, 0);
        assert_ne!(out.flags & flag::CALIBRATION_MISSING, 0);
        let out = s.process(&frame(5, [600; 4]));
        assert_ne!(out.flags & flag::INPUT_GAP, 0);
        // A sideways pull: cells 1 and 3 opposite, no vertical load.
        let out = s.process(&frame(6, [700, 500, 300, 500]));
        assert_ne!(out.flags & flag::NEAR_SINGULARITY, 0);
    }

    #[test]
    fn non_finite_holds_the_last_good_force() {
        let mut cal = rt_config::CalibrationConfig::identity();
        cal.poly_z = [0.0, 1.0, 0.0, f64::INFINITY];
        let mut s = stage(1, ID, Some(&cal));
        let out = s.process(&frame(0, [500; 4]));
        assert_ne!(out.flags & flag::NON_FINITE, 0);
        assert!(out.force_body_n.iter().all(|v| v.is_finite()));
    }
}
