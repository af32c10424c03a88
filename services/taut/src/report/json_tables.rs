//! Any JSON object as markdown tables, so that `summary.json` and the metrics render whatever
//! fields they grow: scalars in a key | value table, an array of objects or an object of
//! objects as one table with a column per inner key, other nested objects as sub-sections.

use serde_json::Value;
use std::fmt::Write;

/// Markdown for `v` under headings of level `level` (`###` for 3).
pub fn render(v: &Value, level: usize) -> String {
    let mut out = String::new();
    render_into(&mut out, v, level);
    out
}

fn render_into(out: &mut String, v: &Value, level: usize) {
    let Value::Object(map) = v else {
        let _ = writeln!(out, "{}\n", cell(v));
        return;
    };
    let scalars: Vec<(&String, &Value)> = map.iter().filter(|(_, v)| is_flat(v)).collect();
    if !scalars.is_empty() {
        out.push_str("| key | value |\n|---|---|\n");
        for (k, v) in scalars {
            let _ = writeln!(out, "| {} | {} |", escape(k), cell(v));
        }
        out.push('\n');
    }
    for (k, v) in map.iter().filter(|(_, v)| !is_flat(v)) {
        let _ = writeln!(out, "{} {}\n", "#".repeat(level.clamp(1, 6)), escape(k));
        match v {
            Value::Array(rows) => table(out, rows.iter().map(|r| (None, r))),
            Value::Object(m) if m.values().all(Value::is_object) => {
                table(out, m.iter().map(|(name, r)| (Some(name.as_str()), r)))
            }
            other => render_into(out, other, level + 1),
        }
    }
}

/// A value shown in one cell: not an object, not an array holding objects.
fn is_flat(v: &Value) -> bool {
    match v {
        Value::Object(m) => m.is_empty(),
        Value::Array(a) => a.iter().all(|x| !x.is_object() && !x.is_array()) || a.is_empty(),
        _ => true,
    }
}

/// One table of rows (objects): a column per key in first-seen order, and a `name` column
/// first when the rows are named.
fn table<'a>(out: &mut String, rows: impl Iterator<Item = (Option<&'a str>, &'a Value)> + Clone) {
    let named = rows.clone().any(|(n, _)| n.is_some());
    let mut keys: Vec<&str> = Vec::new();
    for (_, r) in rows.clone() {
        if let Value::Object(m) = r {
            for k in m.keys() {
                if !keys.contains(&k.as_str()) {
                    keys.push(k);
                }
            }
        }
    }
    if keys.is_empty() {
        let cells: Vec<String> = rows.map(|(_, r)| cell(r)).collect();
        let _ = writeln!(out, "{}\n", cells.join(", "));
        return;
    }
    // serde_json sorts keys: put an identifying column first.
    if let Some(i) = keys.iter().position(|k| matches!(*k, "id" | "name")) {
        let k = keys.remove(i);
        keys.insert(0, k);
    }
    let mut head: Vec<&str> = Vec::new();
    if named {
        head.push("name");
    }
    head.extend(&keys);
    let _ = writeln!(
        out,
        "| {} |",
        head.iter()
            .map(|h| escape(h))
            .collect::<Vec<_>>()
            .join(" | ")
    );
    let _ = writeln!(out, "|{}|", vec!["---"; head.len()].join("|"));
    for (name, r) in rows {
        let mut cells: Vec<String> = Vec::new();
        if named {
            cells.push(escape(name.unwrap_or("")));
        }
        for k in &keys {
            cells.push(r.get(k).map_or_else(|| "–".into(), cell));
        }
        let _ = writeln!(out, "| {} |", cells.join(" | "));
    }
    out.push('\n');
}

/// A value as cell text: numbers rounded for reading, null as "–", arrays joined.
pub fn cell(v: &Value) -> String {
    match v {
        Value::Null => "–".into(),
        Value::Bool(b) => b.to_string(),
        Value::Number(n) if n.is_u64() || n.is_i64() => n.to_string(),
        Value::Number(n) => n.as_f64().map_or_else(|| n.to_string(), number),
        Value::String(s) => escape(s),
        Value::Array(a) => format!("[{}]", a.iter().map(cell).collect::<Vec<_>>().join(", ")),
        Value::Object(_) => escape(&v.to_string()),
    }
}

/// Four significant digits, at most (no exponent for the usual magnitudes).
pub fn number(x: f64) -> String {
    let a = x.abs();
    if a == 0.0 || !(1e-4..1e7).contains(&a) {
        return if a == 0.0 {
            "0".into()
        } else {
            format!("{x:.3e}")
        };
    }
    let digits = (3 - a.log10().floor() as i32).max(0) as usize;
    format!("{x:.digits$}")
}

fn escape(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn objects_become_tables_and_new_fields_show_up() {
        let v = serde_json::json!({
            "scenario": "test-a",
            "sim_s": 41.23456,
            "failure": null,
            "drones": [
                {"id": "uav1", "position_rmse_m": 0.0123456, "new_force_rmse_n": 1.5},
                {"id": "uav2", "position_rmse_m": null}
            ],
            "latency_us": {"uav1_odometry_to_setpoint": {"count": 10, "p50": 412.0}},
            "payload": {"swing_rms_deg": 3.0}
        });
        let md = render(&v, 3);
        assert!(md.contains("| scenario | test-a |"), "{md}");
        assert!(md.contains("| sim_s | 41.23 |"), "{md}");
        assert!(md.contains("| failure | – |"), "{md}");
        // Keys sorted (serde_json's map), the identifying one first.
        assert!(
            md.contains("| id | new_force_rmse_n | position_rmse_m |"),
            "{md}"
        );
        assert!(md.contains("| uav1 | 1.500 | 0.01235 |"), "{md}");
        assert!(md.contains("| uav2 | – | – |"), "{md}");
        assert!(md.contains("| name | count | p50 |"), "{md}");
        assert!(
            md.contains("| uav1_odometry_to_setpoint | 10 | 412.0 |"),
            "{md}"
        );
        assert!(md.contains("### payload"), "{md}");
        assert!(md.contains("| swing_rms_deg | 3.000 |"), "{md}");
    }

    #[test]
    fn numbers_keep_four_significant_digits() {
        assert_eq!(number(1234.5678), "1235");
        assert_eq!(number(0.000123456), "0.0001235");
        assert_eq!(number(-2.5), "-2.500");
        assert_eq!(number(0.0), "0");
        assert_eq!(number(1.0e9), "1.000e9");
    }
}
