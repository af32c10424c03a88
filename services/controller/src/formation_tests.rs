use super::*;

fn vehicle() -> VehicleConfig {
    VehicleConfig::default()
}

fn close(a: &[f64; 3], b: &[f64; 3], tol: f64) -> bool {
    (0..3).all(|i| (a[i] - b[i]).abs() <= tol)
}

/// Equal heights: |T| = m_p g / (2 cos θ), sin θ = (d/2 − a)/L, pulled outwards and up.
#[test]
fn equal_heights_match_the_closed_form() {
    let v = vehicle();
    let w = v.payload_mass_kg * v.gravity_m_s2;
    for d in [0.5, 1.0, 2.0, 2.9] {
        let own = [-1.25, -d / 2.0, -2.1];
        let peer = [-1.25, d / 2.0, -2.1];
        let r = static_tension(&own, &peer, &v);
        let sin = (d / 2.0 - v.payload_anchor_half_span_m) / v.cable_length_m;
        let cos = (1.0 - sin * sin).sqrt();
        let t = w / (2.0 * cos);
        // Own drone west of the peer: it pulls its cable west (−y) and up (−z).
        let expected = [0.0, -t * sin, -t * cos];
        assert_eq!(r.regime, FormationRegime::BothTaut);
        assert!(
            close(&r.own_ned_n, &expected, 1e-12),
            "d {d}: {:?} vs {expected:?}",
            r.own_ned_n
        );
        assert!(close(&r.peer_ned_n, &[0.0, t * sin, -t * cos], 1e-12));
        // Payload anchors hang L cos θ below the drone anchors, midway.
        let z = -2.1 + v.anchor_offset_frd_m[2] + v.cable_length_m * cos;
        assert!(close(&r.payload_anchor_mid_ned_m, &[-1.25, 0.0, z], 1e-12));
    }
    // Test B's start (d = 1 m): sin θ = 0.4/1.5, |T| = 5.08760 N, T = (0, −1.35668, −4.90333) N.
    let r = static_tension(&[-1.25, -0.5, -2.1], &[-1.25, 0.5, -2.1], &v);
    assert!(
        close(&r.own_ned_n, &[0.0, -1.35668, -4.903325], 1e-5),
        "{:?}",
        r.own_ned_n
    );
}

/// Unequal heights, derived by hand: effective anchors A = (0.1, −1.92) and B = A + (2.1, 0.3)
/// in the vertical plane (s east, z down) put P at A + (0.9, 1.2), both cables of 1.5 m taut:
/// u_A = (−0.6, −0.8), u_B = (0.8, −0.6); horizontal balance 0.6 t_A = 0.8 t_B, vertical
/// 0.8 t_A + 0.6 t_B = W give t_A = 0.8 W (higher drone), t_B = 0.6 W.
#[test]
fn unequal_heights_match_the_hand_solution() {
    let v = vehicle();
    let w = v.payload_mass_kg * v.gravity_m_s2;
    let own = [0.0, 0.0, -2.0];
    let peer = [0.0, 2.3, -1.7];
    let r = static_tension(&own, &peer, &v);
    assert_eq!(r.regime, FormationRegime::BothTaut);
    assert!(
        close(&r.own_ned_n, &[0.0, -0.48 * w, -0.64 * w], 1e-9),
        "{:?}",
        r.own_ned_n
    );
    assert!(
        close(&r.peer_ned_n, &[0.0, 0.48 * w, -0.36 * w], 1e-9),
        "{:?}",
        r.peer_ned_n
    );
    assert!(close(&r.payload_anchor_mid_ned_m, &[0.0, 1.0, -0.72], 1e-9));
    // Swapping the roles gives the peer's view; rotating the pair about z rotates T.
    let s = static_tension(&peer, &own, &v);
    assert!(close(&s.own_ned_n, &r.peer_ned_n, 1e-9));
    let r2 = static_tension(&[0.0, 0.0, -2.0], &[2.3, 0.0, -1.7], &v);
    assert!(close(&r2.own_ned_n, &[-0.48 * w, 0.0, -0.64 * w], 1e-9));
}

#[test]
fn one_cable_alone_when_the_peer_is_much_higher_or_lower() {
    let v = vehicle();
    let w = v.payload_mass_kg * v.gravity_m_s2;
    // Peer 1.5 m higher and 0.3 m away: the payload hangs below the peer only.
    let r = static_tension(&[0.0, 0.0, -1.0], &[0.0, 0.3, -2.5], &v);
    assert_eq!(r.regime, FormationRegime::PeerCableOnly);
    assert!(close(&r.own_ned_n, &[0.0; 3], 1e-12));
    assert!(close(&r.peer_ned_n, &[0.0, 0.0, -w], 1e-12));
    let r = static_tension(&[0.0, 0.3, -2.5], &[0.0, 0.0, -1.0], &v);
    assert_eq!(r.regime, FormationRegime::OwnCableOnly);
    assert!(close(&r.own_ned_n, &[0.0, 0.0, -w], 1e-12));
    // One above the other: the higher drone carries it.
    let r = static_tension(&[0.0, 0.0, -2.0], &[0.0, 0.0, -1.0], &v);
    assert_eq!(r.regime, FormationRegime::OwnCableOnly);
}

#[test]
fn too_far_apart_gives_the_flagged_near_horizontal_limit() {
    let v = vehicle();
    let w = v.payload_mass_kg * v.gravity_m_s2;
    let r = static_tension(&[0.0, -2.0, -2.0], &[0.0, 2.0, -2.0], &v);
    assert_eq!(r.regime, FormationRegime::TooFar);
    let sin = NEAR_HORIZONTAL_CHORD;
    let t = w / (2.0 * (1.0 - sin * sin).sqrt());
    assert!(r.own_ned_n.iter().all(|x| x.is_finite()));
    assert!((Vector3::from(r.own_ned_n).norm() - t).abs() < 1e-9);
    assert!(r.own_ned_n[1] < 0.0 && r.own_ned_n[2] < 0.0);
}
