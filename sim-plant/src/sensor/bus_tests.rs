use super::*;
use crate::sensor::params::SensorParams;

const MS: u64 = 1_000_000;
const T0: u64 = 1_000 * MS;

fn ideal_bus(profile: LoadProfile) -> SensorBus {
    SensorBus::new(BusConfig::ideal(), SensorModel::ideal(), profile, T0, 42).unwrap()
}

fn read_code(bus: &mut SensorBus, addr: u8, t: u64) -> (i16, u8) {
    let mut b = [0u8; 3];
    bus.read(addr, &mut b, t).unwrap();
    (i16::from_be_bytes([b[0], b[1]]), b[2])
}

#[test]
fn ideal_z_load_codes() {
    let mut bus = ideal_bus(LoadProfile::Constant([0.0, 0.0, 9.81]));
    let expect = 500 + (160.0 * 1e-3 * 5.0 / 49.033 * 9.81 / 4.0 * 1000.0_f64).round() as i16;
    assert_eq!(expect, 540);
    for addr in DEFAULT_ADDRESSES {
        assert_eq!(read_code(&mut bus, addr, T0 + 5 * MS), (expect, 0x10));
    }
    assert_eq!(bus.true_force_at(T0 + 5 * MS), [0.0, 0.0, 9.81]);
}

#[test]
fn x_load_moves_cells_1_and_3_only() {
    let mut bus = ideal_bus(LoadProfile::Constant([4.0, 0.0, 9.81]));
    let c: Vec<i16> = DEFAULT_ADDRESSES
        .iter()
        .map(|&a| read_code(&mut bus, a, T0 + 5 * MS).0)
        .collect();
    // f1 = -Tz/4 - Tx/2 (more tension), f3 = -Tz/4 + Tx/2.
    let vpn = SensorParams::ideal().volts_per_newton() * 1000.0;
    assert_eq!(c[1], 540);
    assert_eq!(c[3], 540);
    assert_eq!(c[0], (500.0 + vpn * (9.81 / 4.0 + 2.0)).round() as i16);
    assert_eq!(c[2], (500.0 + vpn * (9.81 / 4.0 - 2.0)).round() as i16);
}

#[test]
fn rails_clamp_codes() {
    let mut bus = ideal_bus(LoadProfile::Constant([0.0, 0.0, 1e4]));
    // 4.9 V rail is beyond the ADC's 2.048 V: code sticks at 2047.
    assert_eq!(read_code(&mut bus, 0x68, T0 + 5 * MS).0, 2047);
    bus.set_profile(LoadProfile::Constant([0.0, 0.0, -1e4]), T0);
    assert_eq!(read_code(&mut bus, 0x68, T0 + 10 * MS).0, 0);
}

#[test]
fn unknown_address_and_general_call_read_nack() {
    let mut bus = ideal_bus(LoadProfile::Constant([0.0; 3]));
    assert_eq!(bus.write(0x69, &[0x10], T0), Err(Nack::Address));
    assert_eq!(bus.read(0x00, &mut [0u8; 3], T0), Err(Nack::Address));
    assert_eq!(bus.write(0x00, &[0x07], T0), Err(Nack::Data));
    assert_eq!(bus.unknown_address_nacks(), 2);
    assert_eq!(bus.counters(), [ChipCounters::default(); 4]);
}

#[test]
fn one_shot_general_call_samples_all_cells_at_once() {
    let mut bus = ideal_bus(LoadProfile::Ramp {
        from: [0.0; 3],
        to: [0.0, 0.0, 40.0],
        start_s: 0.0,
        duration_s: 1.0,
    });
    for a in DEFAULT_ADDRESSES {
        bus.write(a, &[0x00], T0 + MS).unwrap(); // one-shot, 12 bit, x1
    }
    bus.write(0x00, &[0x08], T0 + 500 * MS).unwrap();
    let mut codes = Vec::new();
    for a in DEFAULT_ADDRESSES {
        let (code, cfg) = read_code(&mut bus, a, T0 + 505 * MS);
        assert_eq!(cfg, 0x00);
        codes.push(code);
    }
    assert!(codes.iter().all(|&c| c == codes[0]));
    let mids: Vec<u64> = (0..4)
        .map(|i| bus.chip(i).unwrap().result_window().unwrap().mid_ns)
        .collect();
    assert!(mids.iter().all(|&m| m == T0 + 500 * MS + 2_083_333));
    assert_eq!(bus.general_calls(), 1);
    // Input at the window midpoint: 40 N * 0.50208 s.
    let f = 40.0 * (500.0 + 2.083333) / 1000.0;
    let vpn = SensorParams::ideal().volts_per_newton() * 1000.0;
    assert_eq!(codes[0], (500.0 + vpn * f / 4.0).round() as i16);
}

#[test]
fn nack_faults() {
    let mut bus = ideal_bus(LoadProfile::Constant([0.0; 3]));
    let faults = Faults {
        nack_probability: [0.5, 1.0, 0.0, 0.0],
        ..Faults::default()
    };
    bus.set_faults(faults, T0);
    let mut nacks = 0;
    for k in 0..1000 {
        if bus.read(0x68, &mut [0u8; 3], T0 + k * MS).is_err() {
            nacks += 1;
        }
        assert_eq!(bus.write(0x6A, &[0x10], T0 + k * MS), Err(Nack::Address));
        assert!(bus.read(0x6C, &mut [0u8; 3], T0 + k * MS).is_ok());
    }
    assert!((400..600).contains(&nacks), "{nacks}");
    let c = bus.counters();
    assert_eq!((c[0].transactions, c[0].nacks), (1000, nacks));
    assert_eq!((c[1].transactions, c[1].nacks), (1000, 1000));
    assert_eq!((c[2].transactions, c[2].nacks), (1000, 0));
    assert_eq!(c[2].conversions, 239); // 999 ms of conversions from T0
}

#[test]
fn silent_and_stuck_chips() {
    let mut bus = ideal_bus(LoadProfile::Constant([0.0, 0.0, 9.81]));
    let faults = Faults {
        silent: [false, true, false, false],
        stuck: [false, false, true, false],
        ..Faults::default()
    };
    bus.set_faults(faults.clone(), T0 + 2 * MS);
    assert_eq!(
        bus.read(0x6A, &mut [0u8; 3], T0 + 10 * MS),
        Err(Nack::Address)
    );
    assert_eq!(bus.write(0x6A, &[], T0 + 10 * MS), Err(Nack::Address));
    for k in 1..20 {
        let (code, cfg) = read_code(&mut bus, 0x6C, T0 + k * 10 * MS);
        assert_eq!((code, cfg), (0, 0x90));
    }
    assert_eq!(bus.counters()[2].conversions, 0);
    assert_eq!(read_code(&mut bus, 0x68, T0 + 200 * MS).0, 540);
    // General call still works with one silent chip; the silent one ignores it.
    bus.write(0x00, &[0x06], T0 + 300 * MS).unwrap();
    // Recovery.
    bus.set_faults(Faults::default(), T0 + 400 * MS);
    assert_eq!(read_code(&mut bus, 0x6C, T0 + 405 * MS), (540, 0x10));
    assert_eq!(read_code(&mut bus, 0x6A, T0 + 405 * MS).0, 540);
    // Every chip silent: the general call itself is not acknowledged.
    bus.set_faults(
        Faults {
            silent: [true; 4],
            ..Faults::default()
        },
        T0 + 500 * MS,
    );
    assert_eq!(bus.write(0x00, &[0x08], T0 + 500 * MS), Err(Nack::Address));
}

#[test]
fn forced_saturation() {
    let mut bus = ideal_bus(LoadProfile::Constant([0.0, 0.0, 9.81]));
    let faults = Faults {
        forced_input: [
            Some(ForcedInput::RailHigh),
            Some(ForcedInput::RailLow),
            Some(ForcedInput::Volts(-3.0)),
            None,
        ],
        extra_force_body: [0.0, 0.0, 2000.0],
        ..Faults::default()
    };
    bus.set_faults(faults, T0);
    let codes: Vec<i16> = DEFAULT_ADDRESSES
        .iter()
        .map(|&a| read_code(&mut bus, a, T0 + 5 * MS).0)
        .collect();
    assert_eq!(codes, [2047, 0, -2048, 2047]);
    // Ground truth ignores the fault offset.
    assert_eq!(bus.true_force_at(T0), [0.0, 0.0, 9.81]);
}

#[test]
fn deterministic_for_a_seed() {
    let run = |seed: u64| {
        let mut bus = SensorBus::new(
            BusConfig::default(),
            SensorModel::new(SensorParams::default()).unwrap(),
            LoadProfile::Constant([0.3, -0.2, 9.81]),
            T0,
            seed,
        )
        .unwrap();
        let mut out = Vec::new();
        for k in 0..200u64 {
            let mut b = [0u8; 3];
            let addr = DEFAULT_ADDRESSES[(k % 4) as usize];
            if bus.read(addr, &mut b, T0 + k * MS).is_ok() {
                out.extend_from_slice(&b);
            }
        }
        out
    };
    assert_eq!(run(5), run(5));
    assert_ne!(run(5), run(6));
}

#[test]
fn bad_config_and_backwards_time() {
    let mk = |config| {
        SensorBus::new(
            config,
            SensorModel::ideal(),
            LoadProfile::Constant([0.0; 3]),
            0,
            1,
        )
    };
    let dup = BusConfig {
        addresses: [0x68, 0x68, 0x6C, 0x6E],
        ..BusConfig::ideal()
    };
    assert_eq!(mk(dup).unwrap_err(), BusConfigError::DuplicateAddress(0x68));
    let gc = BusConfig {
        addresses: [0x00, 0x6A, 0x6C, 0x6E],
        ..BusConfig::ideal()
    };
    assert_eq!(mk(gc).unwrap_err(), BusConfigError::BadAddress(0x00));
    let mut bus = ideal_bus(LoadProfile::Constant([0.0; 3]));
    bus.read(0x68, &mut [0u8; 3], T0 + 10 * MS).unwrap();
    // An older timestamp counts as the newest seen.
    bus.write(0x68, &[0x10], T0).unwrap();
    assert_eq!(
        bus.chip(0).unwrap().result_window().unwrap().end_ns,
        T0 + 8_333_333
    );
    bus.advance_to(T0 + 10 * MS + 4_166_667);
    assert_eq!(
        bus.chip(0).unwrap().result_window().unwrap().start_ns,
        T0 + 10 * MS
    );
}
