use super::*;

const P240: f64 = 1e9 / 240.0;

fn read3(chip: &mut Mcp3423, t: u64, v: f64) -> [u8; 3] {
    let mut buf = [0u8; 3];
    chip.read(&mut buf, t, &mut |_, _| v);
    buf
}

#[test]
fn power_on_config_and_first_conversion() {
    let mut chip = Mcp3423::new(0, 0.0, 1_000);
    assert_eq!(chip.config_byte(), 0x90);
    assert!(chip.is_continuous());
    assert_eq!(chip.resolution_bits(), 12);
    // Before the first conversion ends: RDY=1, data 0.
    let b = read3(&mut chip, 1_000 + 4_000_000, 0.5);
    assert_eq!(b, [0, 0, 0x90]);
    // After: RDY=0, 500 mV -> code 500.
    let b = read3(&mut chip, 1_000 + 4_200_000, 0.5);
    assert_eq!(b, [0x01, 0xF4, 0x10]);
    let w = chip.result_window().unwrap();
    assert_eq!(w.start_ns, 1_000);
    assert_eq!(w.mid_ns, 1_000 + (P240 / 2.0).round() as u64);
    assert_eq!(w.end_ns, 1_000 + P240.round() as u64);
}

#[test]
fn continuous_rdy_sequencing() {
    let mut chip = Mcp3423::new(0, 0.0, 0);
    let mut ready_times = Vec::new();
    let mut last_mid = 0;
    // Poll every 0.1 ms for 50 ms.
    for i in 1..=500u64 {
        let t = i * 100_000;
        let mut buf = [0u8; 4];
        chip.read(&mut buf, t, &mut |_, mid| mid as f64 * 1e-9);
        // The config byte repeats.
        assert_eq!(buf[2], buf[3]);
        if buf[2] & 0x80 == 0 {
            ready_times.push(t);
            let w = chip.result_window().unwrap();
            assert!(w.end_ns <= t && w.mid_ns > last_mid);
            last_mid = w.mid_ns;
            // A second read right away: RDY=1, same data.
            let mut again = [0u8; 3];
            chip.read(&mut again, t, &mut |_, _| 9.0);
            assert_eq!(again[2] & 0x80, 0x80);
            assert_eq!(again[..2], buf[..2]);
        }
    }
    assert_eq!(ready_times.len(), 12); // 50 ms / 4.1667 ms
    for pair in ready_times.windows(2) {
        let dt = pair[1] - pair[0];
        assert!((4_100_000..=4_200_000).contains(&dt), "{dt}");
    }
    assert_eq!(chip.conversions(), 12);
}

#[test]
fn twelve_bit_codes_clamp_and_sign_extend() {
    let chip = Mcp3423::new(0, 0.0, 0);
    assert_eq!(chip.volts_to_code(0.0004), 0);
    assert_eq!(chip.volts_to_code(0.0006), 1);
    assert_eq!(chip.volts_to_code(2.047), 2047);
    assert_eq!(chip.volts_to_code(4.9), 2047);
    assert_eq!(chip.volts_to_code(-5.0), -2048);
    assert_eq!(chip.volts_to_code(f64::NAN), 0);
    let mut chip = Mcp3423::new(0, 0.0, 0);
    let b = read3(&mut chip, 5_000_000, -0.002);
    assert_eq!(i16::from_be_bytes([b[0], b[1]]), -2);
    assert_eq!(b[0], 0xFF);
    let mut chip = Mcp3423::new(0, 0.0, 0);
    let b = read3(&mut chip, 5_000_000, 3.0);
    assert_eq!([b[0], b[1]], [0x07, 0xFF]);
}

#[test]
fn gain_and_resolution() {
    let mut chip = Mcp3423::new(0, 0.0, 0);
    // Continuous, 12 bit, gain x4.
    chip.write(&[0x12], 0, &mut |_, _| 0.0);
    assert_eq!(chip.pga_gain(), 4);
    assert_eq!(chip.volts_to_code(0.1), 400);
    assert_eq!(chip.volts_to_code(0.6), 2047);
    // 18 bit, gain x1: 3 data bytes, 3.75 SPS.
    chip.write(&[0x1C], 0, &mut |_, _| 0.0);
    assert_eq!(chip.resolution_bits(), 18);
    assert!((chip.period_ns() - 1e9 / 3.75).abs() < 1e-6);
    let mut buf = [0u8; 5];
    chip.read(&mut buf, 270_000_000, &mut |_, _| -0.001);
    // -0.001 V / 15.625 uV = -64 -> 0xFFFFC0, sign-extended into the top byte.
    assert_eq!(buf, [0xFF, 0xFF, 0xC0, 0x1C, 0x1C]);
}

#[test]
fn config_write_restarts_and_clears_rdy() {
    let mut chip = Mcp3423::new(0, 0.0, 0);
    chip.advance(5_000_000, &mut |_, _| 0.1);
    assert!(chip.has_unread_result());
    chip.write(&[0x10], 6_000_000, &mut |_, _| 0.1);
    assert!(!chip.has_unread_result());
    assert_eq!(read3(&mut chip, 10_000_000, 0.2)[2], 0x90);
    let b = read3(&mut chip, 6_000_000 + 4_166_667, 0.2);
    assert_eq!((b[2], i16::from_be_bytes([b[0], b[1]])), (0x10, 200));
    assert_eq!(chip.result_window().unwrap().start_ns, 6_000_000);
}

#[test]
fn one_shot_timing() {
    let mut chip = Mcp3423::new(0, 0.0, 0);
    let mut input = |_: usize, _: u64| 0.25;
    // One-shot config without RDY: nothing runs.
    chip.write(&[0x00], 1_000_000, &mut input);
    chip.advance(100_000_000, &mut input);
    assert_eq!(chip.conversions(), 0);
    // Start one at 100 ms.
    chip.write(&[0x80], 100_000_000, &mut input);
    assert_eq!(read3(&mut chip, 104_000_000, 0.25)[2], 0x80);
    let b = read3(&mut chip, 104_200_000, 0.25);
    assert_eq!((b[2], i16::from_be_bytes([b[0], b[1]])), (0x00, 250));
    let w = chip.result_window().unwrap();
    assert_eq!(w.start_ns, 100_000_000);
    assert_eq!(w.mid_ns, 100_000_000 + (P240 / 2.0).round() as u64);
    // Only one conversion.
    chip.advance(200_000_000, &mut input);
    assert_eq!(chip.conversions(), 1);
    assert_eq!(read3(&mut chip, 200_000_000, 0.25)[2], 0x80);
}

#[test]
fn general_call_conversion_aligns_chips() {
    let mut chips: Vec<Mcp3423> = (0..4)
        .map(|i| Mcp3423::new(i, 0.001 * i as f64, 0))
        .collect();
    let mut input = |i: usize, _: u64| 0.1 * i as f64;
    for c in &mut chips {
        c.write(&[0x00], 1_000, &mut input);
    }
    for c in &mut chips {
        c.general_call(GeneralCall::Conversion, 50_000_000, &mut input);
    }
    for c in &mut chips {
        let mut b = [0u8; 3];
        c.read(&mut b, 60_000_000, &mut input);
        assert_eq!(b[2] & 0x80, 0);
        assert_eq!(i16::from_be_bytes([b[0], b[1]]), 100 * c.index() as i16);
        let w = c.result_window().unwrap();
        assert_eq!(w.start_ns, 50_000_000);
        let expect = (P240 * (1.0 + c.osc_error()) / 2.0).round() as u64;
        assert_eq!(w.mid_ns - 50_000_000, expect);
    }
}

#[test]
fn general_call_reset() {
    let mut chip = Mcp3423::new(0, 0.0, 0);
    chip.write(&[0x0F], 0, &mut |_, _| 0.0);
    chip.general_call(GeneralCall::Latch, 1_000, &mut |_, _| 0.0);
    assert_eq!(chip.config_byte(), 0x8F);
    chip.general_call(GeneralCall::Reset, 2_000, &mut |_, _| 0.0);
    assert_eq!(chip.config_byte(), 0x90);
    assert_eq!(chip.result_window(), None);
    chip.advance(2_000 + 4_166_667, &mut |_, _| 0.0);
    assert_eq!(chip.result_window().unwrap().start_ns, 2_000);
    assert_eq!(GeneralCall::from_byte(0x08), Some(GeneralCall::Conversion));
    assert_eq!(GeneralCall::from_byte(0x07), None);
}

#[test]
fn oscillator_error_changes_the_period() {
    let mut fast = Mcp3423::new(0, -0.002, 0);
    let mut slow = Mcp3423::new(1, 0.002, 0);
    let mut nominal = Mcp3423::new(2, 0.0, 0);
    let ten_seconds = 10_000_000_000;
    for c in [&mut fast, &mut slow, &mut nominal] {
        c.advance(ten_seconds, &mut |_, _| 0.0);
    }
    // 2400 / (1 -+ 0.002) conversions in ten seconds.
    assert_eq!(nominal.conversions(), 2400);
    assert_eq!(fast.conversions(), 2404);
    assert_eq!(slow.conversions(), 2395);
    let t = 100 * P240 as u64 + 1_000_000;
    let mut a = Mcp3423::new(0, 0.002, 0);
    a.advance(t, &mut |_, _| 0.0);
    let w = a.result_window().unwrap();
    assert_eq!(w.end_ns, (100.0 * P240 * 1.002).round() as u64);
    assert_eq!(w.end_ns - w.start_ns, (P240 * 1.002).round() as u64);
}

#[test]
fn stuck_chip_never_finishes() {
    let mut chip = Mcp3423::new(0, 0.0, 0);
    let b = read3(&mut chip, 5_000_000, 0.3);
    assert_eq!(b[2], 0x10);
    chip.set_stuck(true, 6_000_000, &mut |_, _| 0.3);
    for k in 0..10 {
        let b = read3(&mut chip, 10_000_000 + k * 5_000_000, 0.9);
        assert_eq!(b, [0x01, 0x2C, 0x90]);
    }
    assert_eq!(chip.conversions(), 1);
    chip.set_stuck(false, 100_000_000, &mut |_, _| 0.9);
    let b = read3(&mut chip, 105_000_000, 0.9);
    assert_eq!((b[2], i16::from_be_bytes([b[0], b[1]])), (0x10, 900));
}

#[test]
fn channel_two_reads_zero_and_time_going_backwards_is_harmless() {
    let mut chip = Mcp3423::new(0, 0.0, 10_000_000);
    chip.advance(0, &mut |_, _| 1.0);
    assert_eq!(chip.conversions(), 0);
    chip.write(&[0x30], 10_000_000, &mut |_, _| 1.0);
    let b = read3(&mut chip, 20_000_000, 1.0);
    assert_eq!(b, [0, 0, 0x30]);
    chip.advance(u64::MAX, &mut |_, _| 1.0);
    chip.advance(5, &mut |_, _| 1.0);
}
