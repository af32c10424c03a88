//! Load profiles: the cable's pull on the drone as a function of time.
//!
//! The force is in the drone's body frame FRD, in newtons; a load hanging straight below the
//! drone pulls along +z. Time `t_s` is in seconds since the profile's start (the bus's `t0_ns`);
//! before the start every profile holds its initial value.
//!
//! # Formats
//!
//! **Command line**: `"FX,FY,FZ"`, three numbers separated by commas (spaces allowed), a
//! constant force, e.g. `"0,0,9.81"`. See [`LoadProfile::parse_constant`] and
//! [`LoadProfile::from_cli`] (which falls back to a file path).
//!
//! **TOML file** (`*.toml`), one profile per file, chosen by `kind`:
//!
//! ```toml
//! kind = "constant"
//! force = [0.0, 0.0, 9.81]
//! ```
//! ```toml
//! kind = "step"              # `before` until at_s, `after` from at_s on
//! before = [0.0, 0.0, 0.0]
//! after = [0.0, 0.0, 9.81]
//! at_s = 1.0
//! ```
//! ```toml
//! kind = "ramp"              # `from` until start_s, linear, `to` from start_s + duration_s
//! from = [0.0, 0.0, 0.0]
//! to = [0.0, 0.0, 9.81]
//! start_s = 1.0
//! duration_s = 2.0
//! ```
//! ```toml
//! kind = "series"            # piecewise linear, held at both ends; t strictly increasing
//! points = [[0.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 9.81]]   # [t_s, fx, fy, fz]
//! ```
//!
//! **CSV file** (any other extension): one point per line `t,fx,fy,fz` (seconds, newtons),
//! interpreted as a `Series`. An optional header line (the first non-blank line, if it is not
//! numeric, e.g. `t,fx,fy,fz`) is skipped; blank lines and lines starting with `#` are ignored.
//!
//! Every value must be finite. Errors name the line, key or value that was rejected.

use std::path::Path;

use serde::Deserialize;

/// A time-varying force, body FRD, newtons.
#[derive(Debug, Clone, PartialEq)]
pub enum LoadProfile {
    /// The same force at all times.
    Constant([f64; 3]),
    /// `before` for `t < at_s`, `after` from `at_s` on.
    Step {
        before: [f64; 3],
        after: [f64; 3],
        at_s: f64,
    },
    /// `from` until `start_s`, linear to `to` at `start_s + duration_s`, then `to`.
    Ramp {
        from: [f64; 3],
        to: [f64; 3],
        start_s: f64,
        duration_s: f64,
    },
    /// Points `(t_s, force)` with increasing `t_s`, linear between them, held at both ends.
    Series(Vec<(f64, [f64; 3])>),
}

/// Why a profile could not be parsed.
#[derive(Debug, thiserror::Error)]
pub enum ProfileError {
    #[error("force {input:?}: expected \"FX,FY,FZ\" (three finite numbers)")]
    BadConstant { input: String },
    #[error("reading profile file {path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("TOML profile: {0}")]
    Toml(#[from] toml::de::Error),
    #[error("profile key `{key}`: {msg}")]
    BadValue { key: String, msg: String },
    #[error("CSV profile line {line}: {msg}: {text:?}")]
    Csv {
        line: usize,
        text: String,
        msg: String,
    },
    #[error("CSV profile has no data lines")]
    EmptyCsv,
}

/// The TOML representation; converted to [`LoadProfile`] after validation.
#[derive(Debug, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
enum ProfileFile {
    Constant {
        force: [f64; 3],
    },
    Step {
        before: [f64; 3],
        after: [f64; 3],
        at_s: f64,
    },
    Ramp {
        from: [f64; 3],
        to: [f64; 3],
        start_s: f64,
        duration_s: f64,
    },
    Series {
        points: Vec<[f64; 4]>,
    },
}

fn lerp(a: [f64; 3], b: [f64; 3], s: f64) -> [f64; 3] {
    [
        a[0] + (b[0] - a[0]) * s,
        a[1] + (b[1] - a[1]) * s,
        a[2] + (b[2] - a[2]) * s,
    ]
}

fn check_vec(key: &str, v: &[f64]) -> Result<(), ProfileError> {
    match v.iter().find(|x| !x.is_finite()) {
        Some(x) => Err(ProfileError::BadValue {
            key: key.to_string(),
            msg: format!("{x} is not a finite number"),
        }),
        None => Ok(()),
    }
}

impl LoadProfile {
    /// The force at `t_s` seconds after the profile start. A NaN time gives the initial value.
    pub fn force_at(&self, t_s: f64) -> [f64; 3] {
        match self {
            LoadProfile::Constant(f) => *f,
            LoadProfile::Step {
                before,
                after,
                at_s,
            } => {
                if t_s >= *at_s {
                    *after
                } else {
                    *before
                }
            }
            LoadProfile::Ramp {
                from,
                to,
                start_s,
                duration_s,
            } => {
                if t_s.is_nan() || t_s <= *start_s {
                    *from
                } else if t_s >= start_s + duration_s || *duration_s <= 0.0 {
                    *to
                } else {
                    lerp(*from, *to, (t_s - start_s) / duration_s)
                }
            }
            LoadProfile::Series(points) => {
                let (Some(first), Some(last)) = (points.first(), points.last()) else {
                    return [0.0; 3];
                };
                if t_s.is_nan() || t_s <= first.0 {
                    return first.1;
                }
                if t_s >= last.0 {
                    return last.1;
                }
                // First point strictly after t (exists: t < last.0); its predecessor is <= t.
                let i = points
                    .partition_point(|p| p.0 <= t_s)
                    .clamp(1, points.len() - 1);
                let (t_a, f_a) = points[i - 1];
                let (t_b, f_b) = points[i];
                let span = t_b - t_a;
                if span <= 0.0 {
                    f_b
                } else {
                    lerp(f_a, f_b, (t_s - t_a) / span)
                }
            }
        }
    }

    /// Parses a constant force `"FX,FY,FZ"`.
    pub fn parse_constant(s: &str) -> Result<Self, ProfileError> {
        let bad = || ProfileError::BadConstant {
            input: s.to_string(),
        };
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        if parts.len() != 3 {
            return Err(bad());
        }
        let mut f = [0.0; 3];
        for (slot, p) in f.iter_mut().zip(&parts) {
            *slot = p.parse::<f64>().map_err(|_| bad())?;
            if !slot.is_finite() {
                return Err(bad());
            }
        }
        Ok(LoadProfile::Constant(f))
    }

    /// A command-line argument: `"FX,FY,FZ"` if it parses as such, else a profile file path.
    pub fn from_cli(arg: &str) -> Result<Self, ProfileError> {
        match Self::parse_constant(arg) {
            Ok(p) => Ok(p),
            Err(e) if !Path::new(arg).exists() => Err(e),
            Err(_) => Self::from_file(arg),
        }
    }

    /// Reads a profile file: TOML if the extension is `.toml`, CSV otherwise.
    pub fn from_file(path: impl AsRef<Path>) -> Result<Self, ProfileError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| ProfileError::Io {
            path: path.display().to_string(),
            source,
        })?;
        let is_toml = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
        if is_toml {
            Self::from_toml_str(&text)
        } else {
            Self::from_csv_str(&text)
        }
    }

    /// Parses the TOML format described in the module docs.
    pub fn from_toml_str(text: &str) -> Result<Self, ProfileError> {
        let file: ProfileFile = toml::from_str(text)?;
        match file {
            ProfileFile::Constant { force } => {
                check_vec("force", &force)?;
                Ok(LoadProfile::Constant(force))
            }
            ProfileFile::Step {
                before,
                after,
                at_s,
            } => {
                check_vec("before", &before)?;
                check_vec("after", &after)?;
                check_vec("at_s", &[at_s])?;
                Ok(LoadProfile::Step {
                    before,
                    after,
                    at_s,
                })
            }
            ProfileFile::Ramp {
                from,
                to,
                start_s,
                duration_s,
            } => {
                check_vec("from", &from)?;
                check_vec("to", &to)?;
                check_vec("start_s", &[start_s])?;
                check_vec("duration_s", &[duration_s])?;
                if duration_s < 0.0 {
                    return Err(ProfileError::BadValue {
                        key: "duration_s".into(),
                        msg: format!("{duration_s} is negative"),
                    });
                }
                Ok(LoadProfile::Ramp {
                    from,
                    to,
                    start_s,
                    duration_s,
                })
            }
            ProfileFile::Series { points } => {
                if points.is_empty() {
                    return Err(ProfileError::BadValue {
                        key: "points".into(),
                        msg: "no points".into(),
                    });
                }
                let mut out = Vec::with_capacity(points.len());
                for (i, p) in points.iter().enumerate() {
                    let key = format!("points[{i}]");
                    check_vec(&key, p)?;
                    if let Some((t_prev, _)) = out.last() {
                        if p[0] <= *t_prev {
                            return Err(ProfileError::BadValue {
                                key,
                                msg: format!("time {} does not increase (previous {t_prev})", p[0]),
                            });
                        }
                    }
                    out.push((p[0], [p[1], p[2], p[3]]));
                }
                Ok(LoadProfile::Series(out))
            }
        }
    }

    /// Parses the CSV format described in the module docs into a `Series`.
    pub fn from_csv_str(text: &str) -> Result<Self, ProfileError> {
        let mut points: Vec<(f64, [f64; 3])> = Vec::new();
        let mut seen_line = false;
        for (idx, raw) in text.lines().enumerate() {
            let line_no = idx + 1;
            let line = raw.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let first = !seen_line;
            seen_line = true;
            let err = |msg: String| ProfileError::Csv {
                line: line_no,
                text: raw.to_string(),
                msg,
            };
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            let parsed: Result<Vec<f64>, _> = fields.iter().map(|f| f.parse::<f64>()).collect();
            let values = match parsed {
                Ok(v) => v,
                // A non-numeric first line is the header.
                Err(_) if first => continue,
                Err(_) => {
                    let bad = fields
                        .iter()
                        .find(|f| f.parse::<f64>().is_err())
                        .copied()
                        .unwrap_or("");
                    return Err(err(format!("value {bad:?} is not a number")));
                }
            };
            if values.len() != 4 {
                return Err(err(format!(
                    "expected 4 fields t,fx,fy,fz, found {}",
                    values.len()
                )));
            }
            if let Some(x) = values.iter().find(|x| !x.is_finite()) {
                return Err(err(format!("value {x} is not finite")));
            }
            if let Some((t_prev, _)) = points.last() {
                if values[0] <= *t_prev {
                    return Err(err(format!(
                        "time {} does not increase (previous {t_prev})",
                        values[0]
                    )));
                }
            }
            points.push((values[0], [values[1], values[2], values[3]]));
        }
        if points.is_empty() {
            return Err(ProfileError::EmptyCsv);
        }
        Ok(LoadProfile::Series(points))
    }
}

impl std::str::FromStr for LoadProfile {
    type Err = ProfileError;

    /// Same as [`LoadProfile::parse_constant`].
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::parse_constant(s)
    }
}

#[cfg(test)]
#[path = "profile_tests.rs"]
mod tests;
