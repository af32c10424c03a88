use super::*;
use crate::sensor::bus::BusConfig;
use crate::sensor::model::SensorModel;
use crate::sensor::profile::LoadProfile;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

fn bus() -> SensorBus {
    SensorBus::new(
        BusConfig::ideal(),
        SensorModel::ideal(),
        LoadProfile::Constant([0.0, 0.0, 9.81]),
        0,
        3,
    )
    .unwrap()
}

fn handle(bus: &mut SensorBus, req: &[u8], t: u64) -> Vec<u8> {
    let mut resp = [0u8; MAX_RESPONSE];
    let n = handle_request(bus, req, t, &mut resp);
    resp[..n].to_vec()
}

#[test]
fn requests_map_to_bus_transactions() {
    let mut b = bus();
    assert_eq!(handle(&mut b, &[OP_WRITE, 0x68, 1, 0x10], 0), [STATUS_ACK]);
    assert_eq!(
        handle(&mut b, &[OP_READ, 0x68, 4], 5_000_000),
        [STATUS_ACK, 0x02, 0x1C, 0x10, 0x10]
    );
    assert_eq!(handle(&mut b, &[OP_READ, 0x68, 0], 5_000_000), [STATUS_ACK]);
    assert_eq!(
        handle(&mut b, &[OP_READ, 0x42, 3], 0),
        [STATUS_NACK_ADDRESS]
    );
    assert_eq!(
        handle(&mut b, &[OP_WRITE, 0x00, 1, 0x99], 0),
        [STATUS_NACK_DATA]
    );
    assert_eq!(handle(&mut b, &[OP_WRITE, 0x00, 1, 0x08], 0), [STATUS_ACK]);
}

#[test]
fn malformed_requests_are_rejected() {
    let mut b = bus();
    let bad: [&[u8]; 7] = [
        &[],
        &[OP_READ],
        &[OP_READ, 0x68],
        &[OP_READ, 0x68, 3, 0],
        &[OP_WRITE, 0x68, 2, 0x10],
        &[OP_WRITE, 0x68, 0, 0x10],
        &[7, 0x68, 0],
    ];
    for req in bad {
        assert_eq!(handle(&mut b, req, 0), [STATUS_BAD_REQUEST], "{req:?}");
    }
    assert_eq!(b.counters()[0].transactions, 0);
}

#[test]
fn random_bytes_never_panic() {
    let mut b = bus();
    let mut rng = StdRng::seed_from_u64(99);
    let mut req = [0u8; MAX_REQUEST + 1];
    for k in 0..20_000u64 {
        let n = rng.random_range(0..=req.len());
        rng.fill(&mut req[..n]);
        // Bias towards valid ops and addresses so deeper paths run.
        if n > 1 && k % 2 == 0 {
            req[0] = 1 + (req[0] & 1);
            req[1] = [0x00, 0x68, 0x6A, 0x6C, 0x6E][usize::from(req[1]) % 5];
        }
        let resp = handle(&mut b, &req[..n], k * 100_000);
        assert!(!resp.is_empty() && resp[0] <= STATUS_BAD_REQUEST);
    }
}

#[test]
fn error_kinds() {
    use embedded_hal::i2c::Error;
    assert_eq!(
        SimI2cError::Nack(NoAcknowledgeSource::Address).kind(),
        ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address)
    );
    assert_eq!(
        SimI2cError::Nack(NoAcknowledgeSource::Data).kind(),
        ErrorKind::NoAcknowledge(NoAcknowledgeSource::Data)
    );
    assert_eq!(SimI2cError::BadRequest.kind(), ErrorKind::Other);
    assert_eq!(
        SimI2cError::Io(io::ErrorKind::BrokenPipe.into()).kind(),
        ErrorKind::Other
    );
}

#[test]
fn monotonic_clock_advances() {
    let a = monotonic_ns();
    let b = monotonic_ns();
    assert!(a > 0 && b >= a);
}
