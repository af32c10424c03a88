//! The paper's comparison in fast mode: Test A, seed 1, position noise on, for every
//! {proposed, geometric} x {sensor, estimator, truth}. Prints each flight's metrics and checks
//! what physics and the paper say must hold, with bounds set from measurement (seeds 1-3, see
//! README "Baselines"):
//! - no crash and no failsafe in any combination;
//! - the proposed law completes with the sensor and the estimator (with truth on seed 1 its
//!   Move phase times out: the true z error settles at 0.23 m, which with the noise on PX4's
//!   perturbed estimate misses the phase rule's 0.3 m; so completion is not asserted there);
//! - the geometric law's direct compensation leaves the payload swinging: swing RMS after the
//!   drop more than twice the proposed law's with the same source (measured 26-28° vs 6.5-7.8°);
//! - the force the controller acts on is closest to the truth when it is the truth: its RMSE
//!   below the sensor-fed run's (measured 0.47-0.65 N vs 0.93-1.39 N) and below 0.8 N;
//! - the sensor's and the estimator's RMSE against the truth are finite and below 1.5 N
//!   (measured 0.47-0.91 N at 900/60 Hz).

use serde_json::Value;
use std::path::PathBuf;
use std::process::Command;

const TAUT: &str = env!("CARGO_BIN_EXE_taut");

fn fly(law: &str, source: &str) -> (bool, Value) {
    let out: PathBuf = std::env::temp_dir().join(format!(
        "taut-baselines-{}-{law}-{source}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&out);
    let output = Command::new(TAUT)
        .args(["sim", "test-a", "--fast", "--seed", "1"])
        .args(["--law", law, "--tension-source", source])
        .arg("--out")
        .arg(&out)
        .output()
        .expect("start taut sim");
    let text = std::fs::read_to_string(out.join("summary.json")).unwrap_or_else(|e| {
        panic!(
            "{law}/{source}: no summary.json: {e}\n{}{}",
            String::from_utf8_lossy(&output.stdout),
            String::from_utf8_lossy(&output.stderr)
        )
    });
    let _ = std::fs::remove_dir_all(&out);
    (
        output.status.success(),
        serde_json::from_str(&text).unwrap(),
    )
}

fn num(v: &Value) -> Option<f64> {
    v.as_f64()
}

fn rmse(s: &Value, k: usize, key: &str) -> f64 {
    num(&s["drones"][k]["force_rmse"][key]["norm"])
        .unwrap_or_else(|| panic!("drones[{k}].force_rmse.{key} missing: {s:#}"))
}

#[test]
fn test_a_with_every_law_and_tension_source() {
    let mut runs = Vec::new();
    for law in ["proposed", "geometric"] {
        for source in ["sensor", "estimator", "truth"] {
            let (ok, s) = fly(law, source);
            let p = &s["payload"];
            println!(
                "{law:9} {source:9} ok={ok:5} failure={:?} swing_rms={:?}° settle={:?} s \
                 z_ss={:?}/{:?} m max_cable={:?} N",
                s["failure"].as_str(),
                num(&p["swing_rms_deg"]),
                num(&p["settling_time_s"]),
                num(&s["drones"][0]["z_steady_state_error_m"]),
                num(&s["drones"][1]["z_steady_state_error_m"]),
                num(&s["max_cable_force_n"]),
            );
            for k in 0..2 {
                println!(
                    "    uav{} force RMSE vs truth (norm, N): sensor {:.3} estimator {:.3} used {:.3}",
                    k + 1,
                    rmse(&s, k, "sensor_frd_n"),
                    rmse(&s, k, "estimator_frd_n"),
                    rmse(&s, k, "used_ned_n")
                );
            }
            assert_eq!(s["law"], law);
            assert_eq!(s["tension_source"], source);
            assert_eq!(s["crashed"], false, "{law}/{source} crashed");
            assert_eq!(s["failsafe_fired"], false, "{law}/{source}: failsafe");
            assert!(
                num(&p["lifted_at_s"]).is_some(),
                "{law}/{source}: no lift-off"
            );
            for k in 0..2 {
                for key in ["sensor_frd_n", "estimator_frd_n"] {
                    let r = rmse(&s, k, key);
                    assert!(r.is_finite() && r < 1.5, "{law}/{source} uav{k} {key} {r}");
                }
            }
            runs.push((law, source, ok, s));
        }
    }
    let get = |law: &str, source: &str| {
        runs.iter()
            .find(|r| r.0 == law && r.1 == source)
            .map(|r| (r.2, &r.3))
            .unwrap()
    };
    for source in ["sensor", "estimator"] {
        let (ok, s) = get("proposed", source);
        assert!(ok, "proposed/{source} did not complete: {:?}", s["failure"]);
    }
    for source in ["sensor", "estimator", "truth"] {
        let swing = |law| num(&get(law, source).1["payload"]["swing_rms_deg"]).unwrap();
        let (p, g) = (swing("proposed"), swing("geometric"));
        assert!(
            g > 2.0 * p,
            "{source}: geometric swing {g}° vs proposed {p}°"
        );
    }
    for law in ["proposed", "geometric"] {
        for k in 0..2 {
            let truth = rmse(get(law, "truth").1, k, "used_ned_n");
            let sensor = rmse(get(law, "sensor").1, k, "used_ned_n");
            assert!(
                truth < 0.8,
                "{law} uav{k}: used force RMSE with truth {truth} N"
            );
            assert!(
                truth < sensor,
                "{law} uav{k}: truth {truth} N vs sensor {sensor} N"
            );
        }
    }
}
