use super::*;

const Z: [f64; 3] = [0.0, 0.0, 9.81];

#[test]
fn constant_step_ramp() {
    assert_eq!(LoadProfile::Constant(Z).force_at(-5.0), Z);
    let s = LoadProfile::Step {
        before: [0.0; 3],
        after: Z,
        at_s: 1.0,
    };
    assert_eq!(s.force_at(0.999), [0.0; 3]);
    assert_eq!(s.force_at(1.0), Z);
    let r = LoadProfile::Ramp {
        from: [0.0; 3],
        to: [2.0, 0.0, 4.0],
        start_s: 1.0,
        duration_s: 2.0,
    };
    assert_eq!(r.force_at(0.0), [0.0; 3]);
    assert_eq!(r.force_at(2.0), [1.0, 0.0, 2.0]);
    assert_eq!(r.force_at(10.0), [2.0, 0.0, 4.0]);
    assert_eq!(r.force_at(f64::NAN), [0.0; 3]);
}

#[test]
fn series_interpolates_and_holds() {
    let p = LoadProfile::Series(vec![
        (0.0, [0.0; 3]),
        (1.0, [0.0, 0.0, 10.0]),
        (3.0, [4.0; 3]),
    ]);
    assert_eq!(p.force_at(-1.0), [0.0; 3]);
    assert_eq!(p.force_at(0.5), [0.0, 0.0, 5.0]);
    assert_eq!(p.force_at(1.0), [0.0, 0.0, 10.0]);
    assert_eq!(p.force_at(2.0), [2.0, 2.0, 7.0]);
    assert_eq!(p.force_at(99.0), [4.0; 3]);
    assert_eq!(LoadProfile::Series(vec![]).force_at(1.0), [0.0; 3]);
}

#[test]
fn parse_cli_constant() {
    assert_eq!(
        "0, 0,9.81".parse::<LoadProfile>().unwrap(),
        LoadProfile::Constant(Z)
    );
    for bad in ["1,2", "1,2,x", "1,2,3,4", "1,2,inf", ""] {
        let e = LoadProfile::parse_constant(bad).unwrap_err();
        assert!(e.to_string().contains(&format!("{bad:?}")), "{e}");
    }
    assert!(LoadProfile::from_cli("/nonexistent/profile.toml").is_err());
}

#[test]
fn parse_toml_kinds() {
    let r = LoadProfile::from_toml_str(
        "kind = \"ramp\"\nfrom = [0,0,0]\nto = [0,0,9.81]\nstart_s = 1\nduration_s = 2\n",
    )
    .unwrap();
    assert_eq!(r.force_at(2.0), [0.0, 0.0, 9.81 / 2.0]);
    let s =
        LoadProfile::from_toml_str("kind = \"series\"\npoints = [[0,0,0,0],[1,0,0,2]]\n").unwrap();
    assert_eq!(s.force_at(0.5), [0.0, 0.0, 1.0]);
    let c = LoadProfile::from_toml_str("kind = \"constant\"\nforce = [1,2,3]").unwrap();
    assert_eq!(c, LoadProfile::Constant([1.0, 2.0, 3.0]));
    let st = LoadProfile::from_toml_str(
        "kind = \"step\"\nbefore = [0,0,0]\nafter = [0,0,1]\nat_s = 0.5",
    )
    .unwrap();
    assert_eq!(st.force_at(0.6), [0.0, 0.0, 1.0]);
}

#[test]
fn toml_errors_name_the_problem() {
    let e = LoadProfile::from_toml_str(
        "kind = \"ramp\"\nfrom = [0,0,0]\nto = [0,0,1]\nstart_s = 0\nduration_s = -1\n",
    )
    .unwrap_err();
    assert!(e.to_string().contains("duration_s"), "{e}");
    let e = LoadProfile::from_toml_str("kind = \"constant\"\nforce = [0,0,1]\nforse = 2\n")
        .unwrap_err();
    assert!(e.to_string().contains("forse"), "{e}");
    let e = LoadProfile::from_toml_str("kind = \"wobble\"\n").unwrap_err();
    assert!(e.to_string().contains("wobble"), "{e}");
    let e = LoadProfile::from_toml_str("kind = \"series\"\npoints = [[1,0,0,0],[1,0,0,0]]")
        .unwrap_err();
    assert!(e.to_string().contains("points[1]"), "{e}");
    let e = LoadProfile::from_toml_str("kind = \"constant\"\nforce = [0,0,nan]").unwrap_err();
    assert!(e.to_string().contains("force"), "{e}");
}

#[test]
fn parse_csv() {
    let p = LoadProfile::from_csv_str("t,fx,fy,fz\n# comment\n0,0,0,0\n\n2, 0, 0, 4\n").unwrap();
    assert_eq!(p.force_at(1.0), [0.0, 0.0, 2.0]);
    let p = LoadProfile::from_csv_str("0,0,0,1\n").unwrap();
    assert_eq!(p.force_at(5.0), [0.0, 0.0, 1.0]);
    let e = LoadProfile::from_csv_str("t,fx,fy,fz\n0,0,0,0\n1,0,x,0\n").unwrap_err();
    assert!(
        e.to_string().contains("line 3") && e.to_string().contains("\"x\""),
        "{e}"
    );
    let e = LoadProfile::from_csv_str("0,0,0\n").unwrap_err();
    assert!(e.to_string().contains("line 1"), "{e}");
    let e = LoadProfile::from_csv_str("1,0,0,0\n0.5,0,0,0\n").unwrap_err();
    assert!(e.to_string().contains("line 2"), "{e}");
    assert!(matches!(
        LoadProfile::from_csv_str("t,fx,fy,fz\n"),
        Err(ProfileError::EmptyCsv)
    ));
}

#[test]
fn from_file_by_extension() {
    let dir = std::env::temp_dir();
    let pid = std::process::id();
    let toml_path = dir.join(format!("taut-profile-{pid}.toml"));
    let csv_path = dir.join(format!("taut-profile-{pid}.csv"));
    std::fs::write(&toml_path, "kind = \"constant\"\nforce = [0,0,9.81]\n").unwrap();
    std::fs::write(&csv_path, "t,fx,fy,fz\n0,0,0,9.81\n").unwrap();
    let a = LoadProfile::from_cli(toml_path.to_str().unwrap());
    let b = LoadProfile::from_file(&csv_path);
    let _ = std::fs::remove_file(&toml_path);
    let _ = std::fs::remove_file(&csv_path);
    assert_eq!(a.unwrap().force_at(0.0), Z);
    assert_eq!(b.unwrap().force_at(0.0), Z);
}
