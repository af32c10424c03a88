//! Applying a calibration (paper III.C) to cell forces and to the equilibrium force.
//! Fitting one is `calibrate`'s job; this is the part the real-time stage runs.

use rt_config::CalibrationConfig;

/// A calibration ready to apply, or the identity with `missing` set.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// 1 / gamma_j, so the per-sample path multiplies.
    inv_gain: [f64; 4],
    poly: [[f64; 4]; 3],
    crossload: [[f64; 3]; 3],
    missing: bool,
}

impl Calibration {
    pub fn new(cfg: Option<&CalibrationConfig>) -> Self {
        match cfg {
            Some(c) => Self {
                inv_gain: c.cell_gain.map(|g| 1.0 / g),
                poly: [c.poly_x, c.poly_y, c.poly_z],
                crossload: c.crossload,
                missing: false,
            },
            None => Self {
                missing: true,
                ..Self::new(Some(&CalibrationConfig::identity()))
            },
        }
    }

    /// No calibration was configured: outputs are nominal and flagged.
    pub fn is_missing(&self) -> bool {
        self.missing
    }

    /// Per-cell gain correction: f = f_raw / gamma_j.
    pub fn correct_cells(&self, raw: &[f64; 4]) -> [f64; 4] {
        [
            raw[0] * self.inv_gain[0],
            raw[1] * self.inv_gain[1],
            raw[2] * self.inv_gain[2],
            raw[3] * self.inv_gain[3],
        ]
    }

    /// Per-axis regression, then the crossload matrix, on a force in S.
    pub fn correct_force(&self, t: &[f64; 3]) -> [f64; 3] {
        let lin = [
            poly3(&self.poly[0], t[0]),
            poly3(&self.poly[1], t[1]),
            poly3(&self.poly[2], t[2]),
        ];
        mat3_mul(&self.crossload, &lin)
    }
}

/// c0 + c1 x + c2 x^2 + c3 x^3, by Horner.
pub fn poly3(c: &[f64; 4], x: f64) -> f64 {
    ((c[3] * x + c[2]) * x + c[1]) * x + c[0]
}

/// Row-major 3x3 matrix times a vector.
pub fn mat3_mul(m: &[[f64; 3]; 3], v: &[f64; 3]) -> [f64; 3] {
    [
        m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
        m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
        m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_calibration_is_identity_and_says_so() {
        let c = Calibration::new(None);
        assert!(c.is_missing());
        assert_eq!(c.correct_cells(&[1.0, 2.0, 3.0, 4.0]), [1.0, 2.0, 3.0, 4.0]);
        assert_eq!(c.correct_force(&[1.0, -2.0, 3.0]), [1.0, -2.0, 3.0]);
    }

    #[test]
    fn hand_computed_correction() {
        let cfg = CalibrationConfig {
            cell_gain: [2.0, 0.5, 1.0, 1.25],
            poly_x: [0.1, 1.0, 0.0, 0.0],
            poly_y: [0.0, 2.0, 0.0, 0.0],
            poly_z: [0.0, 1.0, 0.01, 0.0],
            crossload: [[1.0, 0.0, 0.1], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        };
        let c = Calibration::new(Some(&cfg));
        assert_eq!(c.correct_cells(&[2.0, 2.0, 2.0, 2.0]), [1.0, 4.0, 2.0, 1.6]);
        // x: 0.1 + 1 = 1.1; y: 2 * 1 = 2; z: 10 + 0.01 * 100 = 11; then x += 0.1 * z = 2.2.
        let t = c.correct_force(&[1.0, 1.0, 10.0]);
        assert!((t[0] - 2.2).abs() < 1e-12 && t[1] == 2.0 && (t[2] - 11.0).abs() < 1e-12);
    }
}
