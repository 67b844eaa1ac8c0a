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
    assert!((g.bias - bias).amax() < 2e-5, "{:?}", g.bias - bias);
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
    assert!(
        (g.bias - bias).amax() < 2e-5,
        "{:?} {:?}",
        g.bias - bias,
        g.report
    );
}
