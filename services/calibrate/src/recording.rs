//! The calibration recording: raw ADC frames of a static bench test, one CSV row per frame.
//!
//! # Format
//!
//! A UTF-8 CSV file whose first non-comment line is exactly the header
//!
//! ```text
//! axis,weight_kg,cycle,direction,step,code1,code2,code3,code4
//! ```
//!
//! then one row per raw frame, in the order the frames were taken:
//!
//! | column | meaning |
//! |---|---|
//! | `axis` | `x`, `y` or `z`: the loaded axis of the sensor frame S (see `TensionSample`) |
//! | `weight_kg` | the reference mass hanging on the anchor, kg (finite, >= 0) |
//! | `cycle` | loading/unloading cycle, 0, 1, ... (the paper does 10) |
//! | `direction` | `up` while loading (weights added), `down` while unloading |
//! | `step` | index of the weight step within the cycle and direction, 0, 1, ... |
//! | `code1`..`code4` | the four MCP3423 codes of cells 1..4, -2048..=2047 |
//!
//! The applied force is `weight_kg * 9.80665` N along **+axis** of S. For `z` the sensor hangs
//! as mounted (anchor down) and the weight hangs from the anchor. For `x` and `y` the sensor is
//! turned so that the weight's pull on the anchor points along +x (resp. +y) of S, with no other
//! component. Blank lines and lines starting with `#` are ignored (use them for notes: date,
//! sensor serial, temperature).
//!
//! The rows of one step (same axis, cycle, direction and step) must be contiguous and carry the
//! same weight: a step is one held load. Recording the peak weight again as the first `down`
//! step (and 0 kg again as the first `up` step of the next cycle) is allowed and gives the
//! hysteresis at the turning points; the fit recognises such "held" steps (same weight as the
//! step before) and keeps them out of the per-cell slopes.
//!
//! A bench session: for each axis (z first, then x and y), for each cycle, load 0, 0.5, ...,
//! 5.5 kg (`up`, steps 0..11) then unload 5.5, ..., 0 kg (`down`, steps 0..11), recording
//! about 3000 frames (12.5 s at 240 Hz) after each weight has stopped swinging.

use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::fmt;
use std::io::{BufRead, Write};
use std::path::Path;

/// Standard gravity: the format's weight -> force conversion.
pub const G: f64 = 9.80665;

/// The exact header line.
pub const HEADER: &str = "axis,weight_kg,cycle,direction,step,code1,code2,code3,code4";

const COLUMNS: [&str; 9] = [
    "axis",
    "weight_kg",
    "cycle",
    "direction",
    "step",
    "code1",
    "code2",
    "code3",
    "code4",
];

/// An axis of the sensor frame S.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    X,
    Y,
    Z,
}

impl Axis {
    pub const ALL: [Axis; 3] = [Axis::X, Axis::Y, Axis::Z];

    /// Index into a force vector `[x, y, z]`.
    pub fn index(self) -> usize {
        self as usize
    }

    pub fn name(self) -> &'static str {
        ["x", "y", "z"][self.index()]
    }

    /// The force vector (S, N) of `weight_kg` pulling along +axis.
    pub fn force(self, weight_kg: f64) -> [f64; 3] {
        let mut f = [0.0; 3];
        f[self.index()] = weight_kg * G;
        f
    }
}

impl fmt::Display for Axis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Loading (weights added) or unloading.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Direction {
    Up,
    Down,
}

impl Direction {
    pub fn name(self) -> &'static str {
        match self {
            Direction::Up => "up",
            Direction::Down => "down",
        }
    }
}

impl fmt::Display for Direction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One held load: all frames of one (axis, cycle, direction, step).
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    pub axis: Axis,
    pub weight_kg: f64,
    pub cycle: u32,
    pub direction: Direction,
    pub step: u32,
    /// Codes of cells 1..4, one entry per frame, in recording order.
    pub codes: Vec<[i16; 4]>,
}

impl Step {
    /// The applied force in S, N.
    pub fn applied_force(&self) -> [f64; 3] {
        self.axis.force(self.weight_kg)
    }

    fn key(&self) -> (Axis, u32, Direction, u32) {
        (self.axis, self.cycle, self.direction, self.step)
    }
}

/// A whole bench session, steps in recording order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Recording {
    pub steps: Vec<Step>,
}

/// What is wrong with a recording file; line and column are 1-based.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    #[error("cannot read or write recording {path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error("{origin}: line {line}, column {column} ({name}): {message}")]
    Field {
        origin: String,
        line: usize,
        column: usize,
        name: &'static str,
        message: String,
    },
    #[error("{origin}: line {line}: {message}")]
    Line {
        origin: String,
        line: usize,
        message: String,
    },
    #[error("{origin}: {message}")]
    Content { origin: String, message: String },
}

impl Recording {
    /// Number of frames over all steps.
    pub fn frames(&self) -> usize {
        self.steps.iter().map(|s| s.codes.len()).sum()
    }

    /// Reads and parses a recording file.
    pub fn load(path: &Path) -> Result<Self, RecordingError> {
        let origin = path.display().to_string();
        let file = std::fs::File::open(path).map_err(|source| RecordingError::Io {
            path: origin.clone(),
            source,
        })?;
        Self::parse(std::io::BufReader::new(file), &origin)
    }

    /// Parses a recording; `origin` names the source in errors.
    pub fn parse<R: BufRead>(reader: R, origin: &str) -> Result<Self, RecordingError> {
        let mut rec = Recording::default();
        let mut header_seen = false;
        // Where each finished step's rows were, to tell a split step from a new one.
        let mut seen: HashMap<(Axis, u32, Direction, u32), usize> = HashMap::new();
        for (i, line) in reader.lines().enumerate() {
            let n = i + 1;
            let line = line.map_err(|source| RecordingError::Io {
                path: format!("{origin} (line {n})"),
                source,
            })?;
            let text = line.trim();
            if text.is_empty() || text.starts_with('#') {
                continue;
            }
            if !header_seen {
                if text != HEADER {
                    return Err(RecordingError::Line {
                        origin: origin.into(),
                        line: n,
                        message: format!("expected the header `{HEADER}`, found `{text}`"),
                    });
                }
                header_seen = true;
                continue;
            }
            let row = parse_row(text, origin, n)?;
            let same_step = rec.steps.last().is_some_and(|s| s.key() == row.key());
            if same_step {
                let last = rec.steps.last_mut().expect("checked above");
                if last.weight_kg != row.weight_kg {
                    return Err(field_err(
                        origin,
                        n,
                        2,
                        format!(
                            "weight {} differs from {} earlier in the same step",
                            row.weight_kg, last.weight_kg
                        ),
                    ));
                }
                last.codes.extend(row.codes);
                continue;
            }
            if let Some(prev) = rec.steps.last() {
                seen.insert(prev.key(), n);
            }
            if let Some(ended) = seen.get(&row.key()) {
                return Err(RecordingError::Line {
                    origin: origin.into(),
                    line: n,
                    message: format!(
                        "step (axis {}, cycle {}, {}, step {}) already ended before line {ended}; \
                         the rows of a step must be contiguous",
                        row.axis, row.cycle, row.direction, row.step
                    ),
                });
            }
            rec.steps.push(row);
        }
        if !header_seen {
            return Err(RecordingError::Content {
                origin: origin.into(),
                message: format!("empty: no header `{HEADER}`"),
            });
        }
        if rec.steps.is_empty() {
            return Err(RecordingError::Content {
                origin: origin.into(),
                message: "no data rows after the header".into(),
            });
        }
        Ok(rec)
    }

    /// Writes the recording in the CSV format, header first.
    pub fn write<W: Write>(&self, mut w: W) -> std::io::Result<()> {
        writeln!(w, "{HEADER}")?;
        for s in &self.steps {
            for c in &s.codes {
                writeln!(
                    w,
                    "{},{},{},{},{},{},{},{},{}",
                    s.axis, s.weight_kg, s.cycle, s.direction, s.step, c[0], c[1], c[2], c[3]
                )?;
            }
        }
        w.flush()
    }

    /// Writes the recording to a file.
    pub fn save(&self, path: &Path) -> Result<(), RecordingError> {
        let io = |source| RecordingError::Io {
            path: path.display().to_string(),
            source,
        };
        let file = std::fs::File::create(path).map_err(io)?;
        self.write(std::io::BufWriter::new(file)).map_err(io)
    }
}

fn field_err(origin: &str, line: usize, column: usize, message: String) -> RecordingError {
    RecordingError::Field {
        origin: origin.into(),
        line,
        column,
        name: COLUMNS[column - 1],
        message,
    }
}

/// One data row, as a one-frame step.
fn parse_row(text: &str, origin: &str, n: usize) -> Result<Step, RecordingError> {
    let fields: Vec<&str> = text.split(',').map(str::trim).collect();
    if fields.len() != COLUMNS.len() {
        return Err(RecordingError::Line {
            origin: origin.into(),
            line: n,
            message: format!(
                "expected {} comma-separated columns ({HEADER}), found {}",
                COLUMNS.len(),
                fields.len()
            ),
        });
    }
    let err = |col: usize, msg: String| field_err(origin, n, col, msg);
    let axis = match fields[0] {
        "x" => Axis::X,
        "y" => Axis::Y,
        "z" => Axis::Z,
        other => return Err(err(1, format!("`{other}` is not one of x, y, z"))),
    };
    let weight_kg: f64 = fields[1]
        .parse()
        .map_err(|_| err(2, format!("`{}` is not a number", fields[1])))?;
    if !(weight_kg.is_finite() && weight_kg >= 0.0) {
        return Err(err(2, format!("{weight_kg} must be finite and >= 0")));
    }
    let cycle: u32 = fields[2]
        .parse()
        .map_err(|_| err(3, format!("`{}` is not a cycle number >= 0", fields[2])))?;
    let direction = match fields[3] {
        "up" => Direction::Up,
        "down" => Direction::Down,
        other => return Err(err(4, format!("`{other}` is not `up` or `down`"))),
    };
    let step: u32 = fields[4]
        .parse()
        .map_err(|_| err(5, format!("`{}` is not a step number >= 0", fields[4])))?;
    let mut codes = [0i16; 4];
    for (k, code) in codes.iter_mut().enumerate() {
        let col = 6 + k;
        let f = fields[col - 1];
        *code = f
            .parse::<i16>()
            .ok()
            .filter(|c| (-2048..=2047).contains(c))
            .ok_or_else(|| err(col, format!("`{f}` is not a 12-bit code -2048..=2047")))?;
    }
    Ok(Step {
        axis,
        weight_kg,
        cycle,
        direction,
        step,
        codes: vec![codes],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Recording, RecordingError> {
        Recording::parse(text.as_bytes(), "test.csv")
    }

    #[test]
    fn groups_contiguous_rows_into_steps() {
        let rec = parse(&format!(
            "# bench 2024-05-01\n{HEADER}\nz,0,0,up,0,500,501,499,500\nz,0,0,up,0,500,500,500,500\n\n\
             z,0.5,0,up,1,540,541,539,540\nz,0.5,0,down,0,541,540,540,540\n"
        ))
        .unwrap();
        assert_eq!(rec.steps.len(), 3);
        assert_eq!(rec.steps[0].codes.len(), 2);
        assert_eq!(rec.steps[2].direction, Direction::Down);
        assert_eq!(rec.frames(), 4);
        assert_eq!(rec.steps[1].applied_force(), [0.0, 0.0, 0.5 * G]);
    }

    #[test]
    fn errors_name_line_and_column() {
        let e = parse(&format!(
            "{HEADER}\nz,0,0,up,0,500,500,500,500\nz,0,0,up,0,500,5x0,500,500\n"
        ))
        .unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains("line 3, column 7 (code2)"), "{msg}");
        let e = parse(&format!("{HEADER}\nw,0,0,up,0,1,2,3,4\n")).unwrap_err();
        assert!(e.to_string().contains("line 2, column 1 (axis)"), "{e}");
        let e = parse(&format!("{HEADER}\nz,-1,0,up,0,1,2,3,4\n")).unwrap_err();
        assert!(e.to_string().contains("column 2 (weight_kg)"), "{e}");
        let e = parse(&format!("{HEADER}\nz,0,0,sideways,0,1,2,3,4\n")).unwrap_err();
        assert!(e.to_string().contains("column 4 (direction)"), "{e}");
        let e = parse(&format!("{HEADER}\nz,0,0,up,0,1,2,3,2048\n")).unwrap_err();
        assert!(e.to_string().contains("column 9 (code4)"), "{e}");
        let e = parse(&format!("{HEADER}\nz,0,0,up,0,1,2,3\n")).unwrap_err();
        assert!(e.to_string().contains("line 2:"), "{e}");
        let e = parse("axis,weight\n").unwrap_err();
        assert!(e.to_string().contains("line 1"), "{e}");
        assert!(parse("# nothing\n").is_err());
        assert!(parse(&format!("{HEADER}\n")).is_err());
    }

    #[test]
    fn a_step_must_be_contiguous_and_hold_one_weight() {
        let e = parse(&format!(
            "{HEADER}\nz,0,0,up,0,1,2,3,4\nz,0.5,0,up,1,1,2,3,4\nz,0,0,up,0,1,2,3,4\n"
        ))
        .unwrap_err();
        assert!(e.to_string().contains("line 4"), "{e}");
        let e = parse(&format!(
            "{HEADER}\nz,0,0,up,0,1,2,3,4\nz,0.5,0,up,0,1,2,3,4\n"
        ))
        .unwrap_err();
        assert!(e.to_string().contains("line 3, column 2"), "{e}");
    }
}
