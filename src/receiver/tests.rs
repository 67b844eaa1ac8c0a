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
use crate::receiver::{ConfigError, ReceiverError};

fn events(r: &mut AttitudeReceiver) -> std::vec::Vec<ReceiverEvent> {
    let mut v = std::vec::Vec::new();
    while let Some(e) = r.pop_event() {
        v.push(e);
    }
    v
}

fn error_deg(r: &AttitudeReceiver, f: &ExampleFlight) -> f32 {
    let a = r.attitude();
    a.q_rb.angle_to(&f.attitude(a.epoch)).to_degrees()
}

extern crate std;

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

#[test]
fn bad_inputs_are_refused_and_leave_the_receiver_unchanged() {
    let mut f = ExampleFlight::new(1);
    let mut r = AttitudeReceiver::new(ExampleFlight::config(true)).unwrap();
    f.fly(&mut r, 0, 300).unwrap();
    let before = r.attitude();
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
