//! The force sensor's mechanics and analog chain: cable pull -> four cell forces -> amplifier
//! output volts at each ADC input.
//!
//! Sensor frame S (paper III.B): origin O at the board centre, z towards the anchor (down when
//! mounted on the drone), cells 1..4 at (-d0,0,0), (0,-d0,0), (+d0,0,0), (0,+d0,0), anchor P at
//! (0,0,h). `T` is the cable's pull on the anchor, in S. The cells measure only normal force;
//! `f_j < 0` is tension and `F_cj = (0,0,f_j)` is cell j's force on the structure. Static
//! equilibrium `T + sum F_cj = 0` (z component only: the lateral pull is carried as shear in
//! the cells' plane, which they do not measure and which adds no x/y moment about O) and
//! `r_P x T + sum r_cj x F_cj = 0` give
//!
//! ```text
//! T_z = -(f1+f2+f3+f4),  T_x = -(d0/h)(f1-f3),  T_y = -(d0/h)(f2-f4)
//! ```
//!
//! Four unknowns, three equations: the structure is statically indeterminate. We close it with
//! the symmetric split `f1+f3 = f2+f4` (a symmetric cross shares the vertical load equally
//! between the two pairs), which gives the inverse in [`split_cell_forces`].
//!
//! Per cell, the analog chain is: ideal cell force `f` -> non-linearity, gain error, hysteresis
//! -> `f'` -> bridge `v = -f' S E / capacity` (positive in tension) -> amplifier
//! `V = ref + offset + gain v + noise`, clamped to the rails -> ADC input volts. Crossload acts
//! before the split (`M T` reaches the cells). Overload beyond the cells' 120 %FS is not
//! modelled; the rails bound the output anyway.

use rand::Rng;
use rand_distr::StandardNormal;

use super::params::{ParamsError, SensorParams};

/// Cell forces (N, negative = tension) that balance the pull `t` (sensor frame) on the anchor,
/// with the symmetric split `f1+f3 = f2+f4`.
pub fn split_cell_forces(t: [f64; 3], d0: f64, h: f64) -> [f64; 4] {
    let quarter = -t[2] / 4.0;
    let k = h / (2.0 * d0);
    [
        quarter - k * t[0],
        quarter - k * t[1],
        quarter + k * t[0],
        quarter + k * t[1],
    ]
}

/// The paper's reconstruction: the pull on the anchor (sensor frame) from the four cell forces.
pub fn tension_from_cells(f: [f64; 4], d0: f64, h: f64) -> [f64; 3] {
    [
        -(d0 / h) * (f[0] - f[2]),
        -(d0 / h) * (f[1] - f[3]),
        -(f[0] + f[1] + f[2] + f[3]),
    ]
}

fn mat_vec(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [
        m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
        m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
        m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
    ]
}

/// Play (backlash) operator of width `width`: the output follows the input only once the input
/// has moved more than `width/2` away from it, so loading and unloading curves differ by
/// `width`. `state` is the last output (None = not yet started: output = input).
fn play(state: &mut Option<f64>, x: f64, width: f64) -> f64 {
    let half = width / 2.0;
    let y = match *state {
        None => x,
        Some(y) if !y.is_finite() => x,
        Some(y) if x > y + half => x - half,
        Some(y) if x < y - half => x + half,
        Some(y) => y,
    };
    *state = Some(y);
    y
}

/// One emulated force sensor, with the per-cell hysteresis state.
#[derive(Debug, Clone)]
pub struct SensorModel {
    params: SensorParams,
    hyst_state: [Option<f64>; 4],
}

impl SensorModel {
    /// Validates `params` and builds the model with fresh hysteresis state.
    pub fn new(params: SensorParams) -> Result<Self, ParamsError> {
        params.validate()?;
        Ok(SensorModel {
            params,
            hyst_state: [None; 4],
        })
    }

    /// The ideal sensor ([`SensorParams::ideal`]).
    pub fn ideal() -> Self {
        SensorModel {
            params: SensorParams::ideal(),
            hyst_state: [None; 4],
        }
    }

    pub fn params(&self) -> &SensorParams {
        &self.params
    }

    /// Forgets the hysteresis history (as after a long rest).
    pub fn reset_hysteresis(&mut self) {
        self.hyst_state = [None; 4];
    }

    /// Body FRD force -> sensor frame, through the mounting rotation.
    pub fn to_sensor_frame(&self, force_body: [f64; 3]) -> [f64; 3] {
        mat_vec(&self.params.mounting, force_body)
    }

    /// Noise-free, imperfection-free cell forces (N, negative = tension) for a pull given in
    /// the sensor frame.
    pub fn ideal_cell_forces(&self, force_sensor: [f64; 3]) -> [f64; 4] {
        split_cell_forces(force_sensor, self.params.d0_m, self.params.h_m)
    }

    /// Cell forces that actually reach the cells (crossload applied), before the per-cell
    /// imperfections, for a body FRD force.
    pub fn loaded_cell_forces(&self, force_body: [f64; 3]) -> [f64; 4] {
        let t = mat_vec(&self.params.crossload, self.to_sensor_frame(force_body));
        self.ideal_cell_forces(t)
    }

    /// ADC input volts of one cell (0..=3) under a body FRD force. Advances that cell's
    /// hysteresis state and draws one normal sample from `rng` (always, so the random stream
    /// does not depend on the parameters). An out-of-range cell reads the reference voltage.
    pub fn cell_volts<R: Rng + ?Sized>(
        &mut self,
        cell: usize,
        force_body: [f64; 3],
        rng: &mut R,
    ) -> f64 {
        let noise: f64 = rng.sample(StandardNormal);
        if cell >= 4 {
            return self.params.reference_v;
        }
        let f = self.loaded_cell_forces(force_body)[cell];
        self.cell_chain(cell, f, noise)
    }

    /// ADC input volts of all four cells (cell order 1..4) under a body FRD force.
    pub fn adc_volts<R: Rng + ?Sized>(&mut self, force_body: [f64; 3], rng: &mut R) -> [f64; 4] {
        let f = self.loaded_cell_forces(force_body);
        let mut out = [0.0; 4];
        for (j, slot) in out.iter_mut().enumerate() {
            let noise: f64 = rng.sample(StandardNormal);
            *slot = self.cell_chain(j, f[j], noise);
        }
        out
    }

    /// Per-cell chain from the force reaching the cell to the ADC input; `noise` ~ N(0,1).
    fn cell_chain(&mut self, j: usize, f: f64, noise: f64) -> f64 {
        let p = &self.params;
        let cap = p.capacity_n;
        let f_nl = f + p.nonlinearity[j] * f * f.abs() / cap;
        let f_g = p.gain_error[j] * f_nl;
        let f_h = play(&mut self.hyst_state[j], f_g, p.hysteresis[j] * cap);
        let bridge_v = -f_h * p.sensitivity_mv_per_v * 1e-3 * p.excitation_v / cap;
        let v =
            p.reference_v + p.zero_offset_v[j] + p.amp_gain * bridge_v + p.noise_std_v[j] * noise;
        // NaN (from a NaN force) goes to the low rail rather than through.
        if v.is_nan() {
            return p.rails_v[0];
        }
        v.clamp(p.rails_v[0], p.rails_v[1])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::SeedableRng;

    fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    }

    #[test]
    fn equilibrium_forces_and_moments_balance() {
        let (d0, h) = (0.03, 0.025);
        let cells = [
            [-d0, 0.0, 0.0],
            [0.0, -d0, 0.0],
            [d0, 0.0, 0.0],
            [0.0, d0, 0.0],
        ];
        let p = [0.0, 0.0, h];
        for t in [
            [0.0, 0.0, 9.81],
            [1.5, -2.0, 7.0],
            [-3.0, 0.4, 12.0],
            [0.0, 1.0, 0.0],
        ] {
            let f = split_cell_forces(t, d0, h);
            // F_cj = (0,0,f_j) is the cells' force on the structure.
            let mut force = t;
            let mut moment = cross(p, t);
            for (c, fj) in cells.iter().zip(f) {
                force[2] += fj;
                let m = cross(*c, [0.0, 0.0, fj]);
                for k in 0..3 {
                    moment[k] += m[k];
                }
            }
            // The normal forces balance T_z and all moments about O; the lateral T_x, T_y are
            // carried as (unmeasured) shear in the cells' plane z = 0, which adds no x/y
            // moment about O (and equal shears add no z moment).
            assert!(force[2].abs() < 1e-12, "force {force:?} for {t:?}");
            assert_eq!([force[0], force[1]], [t[0], t[1]]);
            for k in 0..3 {
                assert!(moment[k].abs() < 1e-12, "moment {moment:?} for {t:?}");
            }
            // The symmetric split and the paper's reconstruction invert each other.
            assert!((f[0] + f[2] - f[1] - f[3]).abs() < 1e-12);
            let back = tension_from_cells(f, d0, h);
            for k in 0..3 {
                assert!((back[k] - t[k]).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn z_load_splits_into_quarters_x_load_moves_cells_1_and_3() {
        let m = SensorModel::ideal();
        assert_eq!(m.ideal_cell_forces([0.0, 0.0, 8.0]), [-2.0; 4]);
        let f = m.ideal_cell_forces([2.0, 0.0, 0.0]);
        // h = d0: f1 = -Tx/2, f3 = +Tx/2.
        assert!((f[0] + 1.0).abs() < 1e-12 && (f[2] - 1.0).abs() < 1e-12);
        assert_eq!((f[1], f[3]), (0.0, 0.0));
        let f = m.ideal_cell_forces([0.0, 2.0, 0.0]);
        assert_eq!((f[0], f[2]), (0.0, 0.0));
        assert!((f[1] + 1.0).abs() < 1e-12 && (f[3] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn ideal_volts_and_rails() {
        let mut m = SensorModel::ideal();
        let mut rng = StdRng::seed_from_u64(1);
        let v = m.adc_volts([0.0, 0.0, 9.81], &mut rng);
        let expect = 0.5 + 160.0 * 1e-3 * 5.0 / (5.0 * 9.80665) * 9.81 / 4.0;
        for x in v {
            assert!((x - expect).abs() < 1e-12, "{x} vs {expect}");
        }
        assert_eq!(m.adc_volts([0.0, 0.0, 0.0], &mut rng), [0.5; 4]);
        // Huge tension: high rail; huge push: low rail.
        assert_eq!(m.adc_volts([0.0, 0.0, 1e4], &mut rng), [4.9; 4]);
        assert_eq!(m.adc_volts([0.0, 0.0, -1e4], &mut rng), [0.0; 4]);
        assert_eq!(m.adc_volts([0.0, 0.0, f64::NAN], &mut rng), [0.0; 4]);
    }

    #[test]
    fn mounting_rotation_applies() {
        let params = SensorParams {
            // Sensor rotated 90 degrees about z: body x -> sensor y.
            mounting: [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
            ..SensorParams::ideal()
        };
        let m = SensorModel::new(params).unwrap();
        assert_eq!(m.to_sensor_frame([1.0, 0.0, 0.0]), [0.0, -1.0, 0.0]);
    }

    #[test]
    fn hysteresis_lags_by_half_width() {
        let params = SensorParams {
            hysteresis: [0.01; 4],
            ..SensorParams::ideal()
        };
        let w = 0.01 * params.capacity_n;
        let vpn = params.volts_per_newton();
        let mut m = SensorModel::new(params).unwrap();
        let mut rng = StdRng::seed_from_u64(1);
        let mut at = |fz: f64| m.cell_volts(0, [0.0, 0.0, fz], &mut rng);
        at(0.0);
        let up = at(20.0); // cell force -5 N, loading (more tension)
        at(40.0);
        let down = at(20.0);
        // Loading: output lags by w/2 (less tension); unloading: leads by w/2.
        let ideal = 0.5 + vpn * 5.0;
        assert!((up - (ideal - vpn * w / 2.0)).abs() < 1e-12);
        assert!((down - (ideal + vpn * w / 2.0)).abs() < 1e-12);
    }

    #[test]
    fn imperfections_change_the_output_deterministically() {
        let run = |seed| {
            let mut m = SensorModel::new(SensorParams::default()).unwrap();
            let mut rng = StdRng::seed_from_u64(seed);
            m.adc_volts([0.5, -0.3, 9.81], &mut rng)
        };
        assert_eq!(run(7), run(7));
        assert_ne!(run(7), run(8));
        let ideal =
            SensorModel::ideal().adc_volts([0.5, -0.3, 9.81], &mut StdRng::seed_from_u64(7));
        assert_ne!(run(7), ideal);
    }
}
