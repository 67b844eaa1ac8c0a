//! The `vector-ekf` experiment: the EKF toolkit, in f32, is consistent over a Monte Carlo of
//! tumbling-body runs and loses nothing to f64.

#[test]
fn vector_ekf_is_consistent_and_f32_matches_f64() {
    let out = host_sim::scenarios::run_by_name("vector-ekf", Some("nominal"), 11).unwrap();
    let m = |k: &str| out.metrics[k].as_f64().unwrap();
    // Average NEES over 200 runs x 1200 epochs: 6 ± a few % for a consistent filter.
    assert!(
        (m("nees_mean") - 6.0).abs() < 0.4,
        "nees_mean {}",
        m("nees_mean")
    );
    // The run-averaged NEES sits in its 95 % interval at roughly 95 % of epochs.
    assert!(
        m("nees_epochs_inside_95") > 0.85,
        "{}",
        m("nees_epochs_inside_95")
    );
    // Actual error matches the filter's own claim within 15 %.
    let ratio = m("rotvec_rms_rad") / m("predicted_rms_rad");
    assert!((0.85..1.15).contains(&ratio), "actual/predicted {ratio}");
    // f32 and f64 runs of the same code differ by far less than the error itself.
    assert!(m("f32_vs_f64_max_rad") < 0.01 * m("rotvec_rms_rad"));
    assert!((m("rotvec_rms_rad") - m("rotvec_rms_rad_f64")).abs() < 0.01 * m("rotvec_rms_rad"));
}
