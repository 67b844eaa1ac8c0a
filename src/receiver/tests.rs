//! Receiver tests: cold start to fine attitude, faults.

use nalgebra::Vector3;

use super::gyro_frame::GyroFrame;
use super::GyroConfig;
use crate::geometry::Quaternion;

#[test]
fn gyro_frame_calibrates_a_bias_against_a_perfect_reference() {
    let mut cfg = GyroConfig::mems(0.01, None);
    cfg.calibration_window_s = 20.0;
    let mut g = GyroFrame::new(cfg).unwrap();
    let bias = Vector3::new(2e-4f32, -1e-4, 1.5e-4);
    let mut truth = Quaternion::<f32>::identity();
    let mut applied = 0;
    for k in 1..=8000u32 {
        let t = k as f32 * 0.01;
        let w = Vector3::new(0.05 * (0.1 * t).sin(), 0.03, 0.01 + 0.02 * (0.05 * t).cos());
        truth = truth * Quaternion::from_rotation_vector(&(w * 0.01));
        g.push(&((w + bias) * 0.01)).unwrap();
        if k % 10 == 0 {
            if !g.calibrating() {
                g.start_calibration(&truth);
            } else if g.add_reference(&truth) {
                applied += 1;
            }
        }
    }
    assert!(applied >= 2, "{applied}");
    let estimate = Vector3::from(g.report.last_bias);
    assert!((estimate - bias).amax() < 2e-5, "{:?}", estimate - bias);
}

#[test]
fn gyro_frame_calibrates_a_bias_on_a_slow_spin() {
    let mut cfg = GyroConfig::mems(0.01, None);
    cfg.calibration_window_s = 60.0;
    let mut g = GyroFrame::new(cfg).unwrap();
    let bias = Vector3::new(4e-4f32, -2.4e-4, 2.4e-4);
    let mut truth = Quaternion::<f32>::from_rotation_vector(&Vector3::new(0.4, -1.0, 2.0));
    let mut applied = 0;
    for k in 1..=30000u32 {
        let w = Vector3::new(0.0, -1.1e-3, 0.0105);
        truth = truth * Quaternion::from_rotation_vector(&(w * 0.01));
        g.push(&((w + bias) * 0.01)).unwrap();
        if k % 10 == 0 {
            if !g.calibrating() {
                g.start_calibration(&truth);
            } else if g.add_reference(&truth) {
                applied += 1;
            }
        }
    }
    assert!(applied >= 2, "{applied} {:?}", g.report);
    let estimate = Vector3::from(g.report.last_bias);
    assert!(
        (estimate - bias).amax() < 2e-5,
        "{:?} {:?}",
        estimate - bias,
        g.report
    );
}

use super::example::{ExampleFlight, NOISE_SIGMA};
use super::{AttitudeReceiver, AttitudeSource, ReceiverEvent};
use crate::attitude::array::ArrayError;
use crate::attitude::one_stage::SatelliteObservation;
use crate::gyro::CalibrationError;
use crate::receiver::{ConfigError, LossReason, ReceiverError};

/// Room for the events a test collects (its receiver queues at most `EVENT_QUEUE` at once).
type Events = heapless::Vec<ReceiverEvent, 1024>;
/// Room for one error/σ ratio per 10 ms of a test's flight.
type Ratios = heapless::Vec<Option<f32>, 4096>;

fn events(r: &mut AttitudeReceiver) -> Events {
    let mut v = Events::new();
    while let Some(e) = r.pop_event() {
        v.push(e).expect("room for the test's events");
    }
    v
}

fn error_deg(r: &AttitudeReceiver, f: &ExampleFlight) -> f32 {
    let a = r.attitude();
    a.q_rb.angle_to(&f.attitude(a.epoch)).to_degrees()
}

#[test]
fn cold_start_hands_over_to_the_fine_filter_with_and_without_a_gyro() {
    for gyro in [true, false] {
        let mut f = ExampleFlight::new(3);
        let mut r = AttitudeReceiver::new(ExampleFlight::config(gyro)).unwrap();
        assert_eq!(r.attitude().source, AttitudeSource::None);
        f.fly(&mut r, 0, 99).unwrap();
        assert_eq!(
            r.attitude().source,
            AttitudeSource::None,
            "no fix before a window"
        );
        f.fly(&mut r, 99, 2000).unwrap();
        let ev = events(&mut r);
        let fix = ev.iter().find_map(|e| match e {
            ReceiverEvent::FirstFix { epoch, satellites } => Some((*epoch, *satellites)),
            _ => None,
        });
        assert_eq!(fix, Some((99, 8)), "{ev:?}");
        let lock = ev.iter().find_map(|e| match e {
            ReceiverEvent::FineLocked { epoch } => Some(*epoch),
            _ => None,
        });
        assert!(lock.is_some_and(|k| k < 400), "gyro {gyro}: {lock:?}");
        let att = r.attitude();
        assert_eq!(att.source, AttitudeSource::Fine);
        let err = error_deg(&r, &f);
        // 8 satellites at 45 dB-Hz, 1 Hz loop: a few hundredths of a degree
        assert!(err < 0.1, "gyro {gyro}: {err}°");
        let sigma = att.covariance.trace().sqrt().to_degrees();
        assert!(
            err < 4.0 * sigma && sigma < 0.1,
            "gyro {gyro}: {err}° vs σ {sigma}°"
        );
        assert_eq!(r.health().satellites_fixed, 8);
        assert!(r.snapshot_estimate().is_some() && r.rigid_body_estimate().is_some());
    }
}

#[test]
fn a_blocked_antenna_is_left_out_and_the_gyro_carries_the_attitude() {
    let mut f = ExampleFlight::new(5);
    let mut r = AttitudeReceiver::new(ExampleFlight::config(true)).unwrap();
    f.fly(&mut r, 0, 1000).unwrap();
    events(&mut r);
    f.antenna_gain = [1.0, 0.0, 1.0];
    f.fly(&mut r, 1000, 3000).unwrap();
    let ev = events(&mut r);
    let blocked = ev.iter().find_map(|e| match e {
        ReceiverEvent::AntennaBlocked { epoch, antenna: 1 } => Some(*epoch),
        _ => None,
    });
    assert!(blocked.is_some_and(|k| k < 1060), "{ev:?}");
    assert_eq!(r.attitude().source, AttitudeSource::GyroCoast);
    assert!(r.health().antenna_blocked[1]);
    assert!(error_deg(&r, &f) < 0.1);
    f.antenna_gain = [1.0; 3];
    f.fly(&mut r, 3000, 4000).unwrap();
    let ev = events(&mut r);
    assert!(ev
        .iter()
        .any(|e| matches!(e, ReceiverEvent::AntennaRestored { antenna: 1, .. })));
    assert!(ev
        .iter()
        .any(|e| matches!(e, ReceiverEvent::AmbiguityFixed { .. })));
    assert_eq!(r.attitude().source, AttitudeSource::Fine);
    assert_eq!(r.health().satellites_fixed, 8);
    assert!(error_deg(&r, &f) < 0.1);
}

#[test]
fn a_cycle_slip_is_found_and_repaired_and_a_bit_flip_is_flagged() {
    let mut f = ExampleFlight::new(9);
    let mut r = AttitudeReceiver::new(ExampleFlight::config(true)).unwrap();
    f.fly(&mut r, 0, 1000).unwrap();
    events(&mut r);
    f.fly(&mut r, 1000, 1440).unwrap();
    // antenna C of satellite 2 turns by one cycle over 80 epochs (a quarter cycle per fine
    // block: the counters follow it, the fine filter's gate leaves the satellite out)
    let mut worst = 0.0f32;
    for (j, k) in (1440..1520).enumerate() {
        f.phase_offset[2][2] = core::f32::consts::TAU * (j as f32 + 1.0) / 80.0;
        f.fly(&mut r, k, k + 1).unwrap();
        worst = worst.max(error_deg(&r, &f));
    }
    f.fly(&mut r, 1520, 1800).unwrap();
    assert!(worst < 0.1, "attitude error {worst}° during the slip");
    let ev = events(&mut r);
    let prn = crate::attitude::example::SKY[2].0;
    assert!(
        ev.iter().any(|e| matches!(e, ReceiverEvent::CycleSlip { prn: p, antenna: 2, cycles: 1, .. } if *p == prn)),
        "{ev:?}"
    );
    assert_eq!(r.health().satellites_fixed, 8);
    // a sign inversion 10 epochs after a bit edge of satellite 4
    let edge = (1900..1920).find(|k| (k + 7 * 4) % 20 == 0).unwrap();
    f.bit_flip = Some((4, edge + 10));
    f.fly(&mut r, 1800, 2200).unwrap();
    let ev = events(&mut r);
    let prn = crate::attitude::example::SKY[4].0;
    assert!(
        ev.iter()
            .any(|e| matches!(e, ReceiverEvent::BitAnomaly { prn: p, .. } if *p == prn)),
        "{ev:?}"
    );
    assert_eq!(r.attitude().source, AttitudeSource::Fine);
    assert!(error_deg(&r, &f) < 0.1);
}

/// A whole cycle turned over exactly one window (epochs 1500–1599, the microsat run's slip):
/// the counter follows it in a straight line, but the window's products turn through a whole
/// cycle and lose their coherence, so the window drops the integer and remembers it; the
/// re-fix one window later reports the slip.
#[test]
fn a_cycle_slip_inside_one_window_is_found_and_repaired() {
    let mut f = ExampleFlight::new(9);
    let mut r = AttitudeReceiver::new(ExampleFlight::config(true)).unwrap();
    f.fly(&mut r, 0, 1500).unwrap();
    events(&mut r);
    for (j, k) in (1500..1600).enumerate() {
        f.phase_offset[2][2] = core::f32::consts::TAU * (j as f32 + 0.5) / 100.0;
        f.fly(&mut r, k, k + 1).unwrap();
    }
    f.phase_offset[2][2] = core::f32::consts::TAU;
    f.fly(&mut r, 1600, 2000).unwrap();
    let ev = events(&mut r);
    let prn = crate::attitude::example::SKY[2].0;
    assert!(
        ev.iter().any(|e| matches!(e, ReceiverEvent::CycleSlip { prn: p, antenna: 2, cycles: 1, .. } if *p == prn)),
        "{ev:?}"
    );
    assert_eq!(r.health().satellites_fixed, 8);
    assert_eq!(r.attitude().source, AttitudeSource::Fine);
    assert!(error_deg(&r, &f) < 0.1);
}

#[test]
fn bad_inputs_are_refused_and_leave_the_receiver_unchanged() {
    let mut f = ExampleFlight::new(1);
    let mut r = AttitudeReceiver::new(ExampleFlight::config(true)).unwrap();
    f.fly(&mut r, 0, 300).unwrap();
    let before = r.attitude();
    let gyro_state = |r: &AttitudeReceiver| {
        let g = r.gyro.as_ref().expect("a gyro");
        (g.samples(), g.at_step(), g.calibrating(), g.report)
    };
    let gyro_before = gyro_state(&r);
    let mut obs = f.observations(300)[0];
    obs.prompt.i[1] = f32::NAN;
    assert_eq!(r.push_observation(300, &obs), Err(ReceiverError::NonFinite));
    obs.prompt.i[1] = 1.0;
    obs.noise_var = 0.0;
    assert_eq!(
        r.push_observation(300, &obs),
        Err(ReceiverError::InvalidInput)
    );
    let stranger = SatelliteObservation {
        id: 99,
        noise_var: NOISE_SIGMA * NOISE_SIGMA,
        ..obs
    };
    assert_eq!(
        r.push_observation(300, &stranger),
        Err(ReceiverError::NoAiding)
    );
    obs.noise_var = NOISE_SIGMA * NOISE_SIGMA;
    assert_eq!(
        r.push_observation(200, &obs),
        Err(ReceiverError::StaleEpoch)
    );
    assert_eq!(
        r.push_gyro_increment(&[f32::INFINITY, 0.0, 0.0]),
        Err(ReceiverError::NonFinite)
    );
    assert_eq!(
        r.push_gyro_increment(&[2.0, 0.0, 0.0]),
        Err(ReceiverError::Gyro(CalibrationError::InputOutOfRange))
    );
    let mut aiding = f.aiding(300);
    aiding[0].los = [2.0, 0.0, 0.0];
    assert_eq!(r.set_aiding(&aiding), Err(ReceiverError::InvalidInput));
    assert_eq!(r.attitude(), before);
    assert_eq!(gyro_state(&r), gyro_before);
    // a degenerate array is refused at construction
    let mut cfg = ExampleFlight::config(true);
    cfg.antennas_m[2] = cfg.antennas_m[1];
    assert_eq!(
        AttitudeReceiver::new(cfg).err(),
        Some(ReceiverError::InvalidConfig(ConfigError::Array(
            ArrayError::CoincidentAntennas
        )))
    );
    // a window that is not a whole number of gyro steps
    let mut cfg = ExampleFlight::config(true);
    cfg.window_epochs = 105;
    assert_eq!(
        AttitudeReceiver::new(cfg).err(),
        Some(ReceiverError::InvalidConfig(ConfigError::OutOfRange {
            field: "window_epochs"
        }))
    );
}

#[test]
fn unknown_line_biases_are_resolved_at_the_cold_start_and_estimated_in_flight() {
    use super::example::LINE_BIAS_RAD;
    let mut f = ExampleFlight::new(5);
    let mut r = AttitudeReceiver::new(ExampleFlight::config(true)).unwrap();
    assert_eq!(r.config().line_bias, None);
    f.fly(&mut r, 0, 3000).unwrap();
    let h = r.health();
    for (p, truth) in LINE_BIAS_RAD.iter().enumerate() {
        let err = crate::geometry::wrap_angle(h.line_bias_rad[p] - truth);
        let sigma = h.line_bias_sigma_rad[p];
        assert!(err.abs() < 0.02, "line bias {p}: error {err} rad");
        assert!(err.abs() < 4.0 * sigma + 1e-3, "{err} vs σ {sigma}");
    }
    assert!(error_deg(&r, &f) < 0.05);
}

/// Flies into a locked fine attitude, then an outage of `gap` epochs (gyro only when
/// `gyro_in_gap`, else nothing at all: an epoch jump), then signals again; returns the
/// events from the outage on and the epochs from the return to the fine attitude.
fn outage(
    gyro: bool,
    gap: u64,
    gyro_in_gap: bool,
) -> (Events, Option<u64>, AttitudeReceiver, ExampleFlight) {
    let mut f = ExampleFlight::new(21);
    let mut r = AttitudeReceiver::new(ExampleFlight::config(gyro)).unwrap();
    f.fly(&mut r, 0, 2000).unwrap();
    assert_eq!(r.attitude().source, AttitudeSource::Fine);
    events(&mut r);
    let back = 2000 + gap;
    if gyro_in_gap {
        f.coast(&mut r, 2000, back).unwrap();
    }
    let mut ev = events(&mut r);
    // signals return (the flight's gyro increments follow the epochs again)
    let mut regained = None;
    for k in (back..back + 3000).step_by(50) {
        f.fly(&mut r, k, k + 50).unwrap();
        ev.extend(events(&mut r));
        if regained.is_none() && r.attitude().source == AttitudeSource::Fine {
            regained = Some(k + 50 - back);
        }
    }
    (ev, regained, r, f)
}

fn lost(ev: &[ReceiverEvent]) -> Option<LossReason> {
    ev.iter().find_map(|e| match e {
        ReceiverEvent::AttitudeLost { reason, .. } => Some(*reason),
        _ => None,
    })
}

#[test]
fn a_short_outage_is_coasted_on_the_gyro_and_resumed_without_a_cold_start() {
    for gap in [1_000u64, 30_000] {
        let (ev, regained, r, f) = outage(true, gap, true);
        assert_eq!(lost(&ev), None, "gap {gap}: {ev:?}");
        assert!(
            regained.is_some_and(|e| e <= 200),
            "gap {gap}: regained after {regained:?} epochs"
        );
        assert!(
            error_deg(&r, &f) < 0.05,
            "gap {gap}: {}°",
            error_deg(&r, &f)
        );
        assert_eq!(r.health().cold_restarts, 0);
    }
}

#[test]
fn a_long_outage_loses_the_attitude_and_the_cold_start_finds_it_again() {
    use super::LossReason;
    // 130 s and an hour on the gyro alone (beyond the 120 s coast limit), an hour without
    // anything (an epoch jump), and 30 s without a gyro at all
    for (gyro, gap, gyro_in_gap, reason) in [
        (true, 130_000u64, true, LossReason::CoastTooLong),
        (true, 3_600_000, true, LossReason::CoastTooLong),
        (true, 3_600_000, false, LossReason::EpochJump),
        (false, 30_000, false, LossReason::EpochJump),
    ] {
        let (ev, regained, r, f) = outage(gyro, gap, gyro_in_gap);
        assert_eq!(lost(&ev), Some(reason), "gap {gap} gyro {gyro}: {ev:?}");
        // the cold start needs one clean window after the return (then the fine filter's
        // first block): under a second, as from switch-on
        assert!(
            regained.is_some_and(|e| e <= 1000),
            "gap {gap} gyro {gyro}: regained after {regained:?} epochs"
        );
        assert!(
            error_deg(&r, &f) < 0.05,
            "gap {gap}: {}°",
            error_deg(&r, &f)
        );
        assert_eq!(r.health().cold_restarts, 1, "gap {gap} gyro {gyro}");
    }
}

/// Flies `from..to` like [`ExampleFlight::fly`] with the gyro increments passed through
/// `fault` (sample index, true increment → what the gyro reports); returns, per 10 epochs,
/// the attitude error over its reported σ (largest axis), `None` without an attitude.
fn fly_with_gyro(
    f: &mut ExampleFlight,
    r: &mut AttitudeReceiver,
    from: u64,
    to: u64,
    fault: impl Fn(u64, [f32; 3]) -> [f32; 3],
) -> Ratios {
    let mut ratios = Ratios::new();
    for k in from..to {
        if k % 100 == 0 {
            r.set_aiding(&f.aiding(k)).unwrap();
        }
        if k > 0 && k % 10 == 0 {
            let n = k / 10 - 1;
            r.push_gyro_increment(&fault(n, f.gyro_increment(n)))
                .unwrap();
        }
        for o in f.observations(k).iter() {
            r.push_observation(k, o).unwrap();
        }
        if k % 10 == 9 {
            r.close_through(k);
            let a = r.attitude();
            ratios
                .push((a.source != AttitudeSource::None).then(|| {
                    let truth = f.attitude(a.epoch);
                    let e = (a.q_rb.conjugate() * truth).to_rotation_vector();
                    let sigma = a.covariance.diagonal().map(|v| v.max(0.0).sqrt());
                    (0..3)
                        .map(|i| e[i].abs() / sigma[i].max(1e-9))
                        .fold(0.0, f32::max)
                }))
                .expect("room for the flight's ratios");
        }
    }
    ratios
}

#[test]
fn a_faulty_gyro_is_excluded_and_the_reported_sigma_keeps_covering_the_error() {
    let fast = |_: u64, _: [f32; 3]| [0.05, 0.0, 0.0]; // 5 rad/s
    let stuck = |_: u64, _: [f32; 3]| [0.0; 3];
    let scale = |_: u64, t: [f32; 3]| t.map(|v| 1.5 * v);
    let spike = |n: u64, t: [f32; 3]| if n == 6250 { [0.5, 0.0, 0.0] } else { t };
    type Fault<'a> = &'a dyn Fn(u64, [f32; 3]) -> [f32; 3];
    let faults: [(&str, Fault, bool); 4] = [
        ("5 rad/s", &fast, true),
        ("stuck", &stuck, true),
        ("scale ×1.5", &scale, true),
        ("one spike", &spike, false),
    ];
    for (name, fault, excluded) in faults {
        let mut f = ExampleFlight::new(31);
        let mut r = AttitudeReceiver::new(ExampleFlight::config(true)).unwrap();
        // a minute to converge (the gyro bias is known to its random walk by then), then
        // 10 s of the fault, then 15 s of a good gyro
        f.fly(&mut r, 0, 60_000).unwrap();
        events(&mut r);
        let mut ratios = fly_with_gyro(&mut f, &mut r, 60_000, 70_000, fault);
        ratios.extend(fly_with_gyro(&mut f, &mut r, 70_000, 85_000, |_, t| t));
        let ev = events(&mut r);
        let was_excluded = ev
            .iter()
            .any(|e| matches!(e, ReceiverEvent::GyroExcluded { .. }));
        assert_eq!(was_excluded, excluded, "{name}: {ev:?}");
        if excluded {
            assert!(
                ev.iter()
                    .any(|e| matches!(e, ReceiverEvent::GyroRestored { .. })),
                "{name}: {ev:?}"
            );
        }
        let with: heapless::Vec<f32, 4096> = ratios.iter().flatten().copied().collect();
        let covered = with.iter().filter(|&&x| x <= 3.0).count() as f32 / with.len() as f32;
        let worst = with.iter().fold(0.0f32, |a, &b| a.max(b));
        // (a fault is seen only once the error it causes exceeds the snapshot's own noise,
        // a fraction of a second; the flight's fault runs are held to 99 %)
        assert!(
            covered >= 0.95,
            "{name}: error ≤ 3σ in only {covered:.3} of the epochs (worst {worst:.1}σ)"
        );
        assert!(worst < 20.0, "{name}: an error of {worst:.1}σ");
        assert!(
            with.len() as f32 >= 0.99 * ratios.len() as f32,
            "{name}: attitude unavailable too often"
        );
        assert!(
            error_deg(&r, &f) < 0.05,
            "{name}: {}° at the end",
            error_deg(&r, &f)
        );
        assert!(!r.health().gyro_excluded, "{name}: still excluded");
    }
}

/// Issue 15: `ExampleFlight::observations(u64::MAX)` overflowed (`epoch + 7 i`, the data
/// bit's index). The flight is now defined for every epoch: eight finite observations.
#[test]
fn example_flight_observations_at_u64_max_do_not_overflow() {
    let mut f = ExampleFlight::new(4);
    for epoch in [u64::MAX, u64::MAX - 1, u64::MAX - 20] {
        let obs = f.observations(epoch);
        assert_eq!(obs.len(), 8, "epoch {epoch}");
        for o in obs.iter() {
            let values = o.prompt.i.iter().chain(o.prompt.q.iter());
            assert!(values.copied().all(f32::is_finite), "epoch {epoch}: {o:?}");
        }
        let q = f.attitude(epoch);
        assert!([q.w, q.x, q.y, q.z].iter().all(|v| v.is_finite()));
    }
}

/// Issue 15: epochs near `u64::MAX` overflowed in the epoch buffer (`epoch + 1`,
/// `first + 1`, `open + window_epochs`): with overflow checks a panic, in release a wrap
/// that defeated the stale-epoch guard. Now an epoch beyond [`super::epoch::MAX_EPOCH`] is
/// refused, closing stops at that epoch, and every closed epoch stays closed.
#[test]
fn epochs_near_u64_max_neither_overflow_nor_reopen_a_closed_epoch() {
    use super::epoch::MAX_EPOCH;
    for gyro in [false, true] {
        let mut f = ExampleFlight::new(6);
        let mut r = AttitudeReceiver::new(ExampleFlight::config(gyro)).unwrap();
        r.set_aiding(&f.aiding(0)).unwrap();
        let obs = f.observations(0)[0];
        for e in [u64::MAX, u64::MAX - 1, MAX_EPOCH + 1] {
            assert_eq!(
                r.push_observation(e, &obs),
                Err(ReceiverError::EpochOutOfRange)
            );
        }
        assert_eq!(r.epoch(), None);
        for e in MAX_EPOCH - 3..=MAX_EPOCH {
            for o in f.observations(e).iter() {
                r.push_observation(e, o).unwrap();
            }
        }
        // closing through u64::MAX stops at the last epoch the receiver accepts
        r.close_through(u64::MAX);
        assert_eq!(r.epoch(), Some(MAX_EPOCH), "gyro {gyro}");
        let before = r.attitude();
        r.close_through(u64::MAX);
        r.close_through(MAX_EPOCH);
        assert_eq!(r.epoch(), Some(MAX_EPOCH));
        assert_eq!(r.attitude(), before);
        // the stale-epoch guard holds at the top: every closed epoch is refused
        for e in [MAX_EPOCH, MAX_EPOCH - 1, MAX_EPOCH - 3, 0] {
            assert_eq!(
                r.push_observation(e, &obs),
                Err(ReceiverError::StaleEpoch),
                "epoch {e}"
            );
        }
        let q = r.attitude().q_rb;
        assert!([q.w, q.x, q.y, q.z].iter().all(|v| v.is_finite()));
    }
    // a receiver in flight, then a jump to the top: the earlier epochs stay closed
    let mut f = ExampleFlight::new(6);
    let mut r = AttitudeReceiver::new(ExampleFlight::config(true)).unwrap();
    f.fly(&mut r, 0, 1000).unwrap();
    assert_eq!(r.attitude().source, AttitudeSource::Fine);
    let obs = f.observations(MAX_EPOCH)[0];
    r.push_observation(MAX_EPOCH, &obs).unwrap();
    r.close_through(u64::MAX);
    assert_eq!(r.epoch(), Some(MAX_EPOCH));
    assert_eq!(
        r.push_observation(999, &obs),
        Err(ReceiverError::StaleEpoch)
    );
    assert!(events(&mut r)
        .iter()
        .any(|e| matches!(e, ReceiverEvent::AttitudeLost { .. })));
}
