//! The sensor's static equilibrium (paper III.B), in the sensor frame S of
//! [`shared_types::TensionSample`]: T_z = -(f1+f2+f3+f4), T_x = -(d0/h)(f1-f3),
//! T_y = -(d0/h)(f2-f4), with f_j < 0 in tension.

/// Where the cells and the anchor sit: cells at distance `d0_m` from the board centre, the
/// anchor `h_m` below it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geometry {
    pub d0_m: f64,
    pub h_m: f64,
}

impl Geometry {
    /// Cable pull on the anchor in S from the four cell forces.
    pub fn force_from_cells(&self, f: &[f64; 4]) -> [f64; 3] {
        let k = self.d0_m / self.h_m;
        [
            -k * (f[0] - f[2]),
            -k * (f[1] - f[3]),
            -(f[0] + f[1] + f[2] + f[3]),
        ]
    }

    /// The cell forces a pull `t` (in S) produces with the symmetric split f1+f3 = f2+f4
    /// (the minimum-norm solution; the cross support has no other load path). Used by
    /// calibration to give each cell its reference share.
    pub fn cells_from_force(&self, t: &[f64; 3]) -> [f64; 4] {
        let q = self.h_m / (2.0 * self.d0_m);
        let base = -t[2] / 4.0;
        [
            base - q * t[0],
            base - q * t[1],
            base + q * t[0],
            base + q * t[1],
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    }

    #[test]
    fn hanging_load_puts_all_cells_in_tension() {
        let g = Geometry {
            d0_m: 0.03,
            h_m: 0.03,
        };
        let f = g.cells_from_force(&[0.0, 0.0, 9.81]);
        assert!(f.iter().all(|&x| (x + 9.81 / 4.0).abs() < 1e-12));
        assert_eq!(g.force_from_cells(&f), [0.0, 0.0, 9.81]);
    }

    #[test]
    fn forces_and_moments_balance() {
        // T + sum F_cj = 0 and r_P x T + sum r_cj x F_cj = 0 with the cells' force on the
        // structure F_cj = (0, 0, f_j): the frame S described on TensionSample.
        let g = Geometry {
            d0_m: 0.03,
            h_m: 0.021,
        };
        let t = [1.5, -2.0, 7.0];
        let f = g.cells_from_force(&t);
        let d = g.d0_m;
        let cells = [[-d, 0.0, 0.0], [0.0, -d, 0.0], [d, 0.0, 0.0], [0.0, d, 0.0]];
        let mut m = cross([0.0, 0.0, g.h_m], t);
        let mut fz = t[2];
        for (r, fj) in cells.iter().zip(f) {
            let mj = cross(*r, [0.0, 0.0, fj]);
            for k in 0..3 {
                m[k] += mj[k];
            }
            fz += fj;
        }
        assert!(m.iter().all(|x| x.abs() < 1e-12), "moment {m:?}");
        assert!(fz.abs() < 1e-12);
        let back = g.force_from_cells(&f);
        for k in 0..3 {
            assert!((back[k] - t[k]).abs() < 1e-12);
        }
    }
}
