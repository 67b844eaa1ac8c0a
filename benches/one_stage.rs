//! Host cost of one epoch of paper 003's one-stage filter (criterion): 12 satellites (the
//! receiver's maximum) with every state on (three angles, rates, two line biases), both update
//! forms, and the paper's configuration (8 satellites, β only). The target's instruction counts
//! of the same step come from the firmware under `examples/firmware` (printed by `.ci/run`).
//! Also the adapter from the tracking channels: 12 `TrackingEpoch<3>`s → observations.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use gnss_attitude::attitude::array::AntennaArray;
use gnss_attitude::attitude::one_stage::{
    EstimatedAngles, FilterMode, OneStageConfig, OneStageFilter, PhaseModel, Prior, PromptIq,
    SatelliteObservation, MAX_SATELLITES,
};
use gnss_attitude::geometry::Paper003Angles;
use gnss_attitude::receiver::{AdapterConfig, EpochClock, ObservationAdapter};
use gnss_attitude::signal::{EpochCorrelations, Iq, Prn, Taps};
use gnss_attitude::tracking::{ChannelState, LockFlags, TrackingEpoch};
use nalgebra::Vector3;

/// Twelve locked channels' epochs (prompt and noise taps of three antennas).
fn tracking_epochs() -> Vec<TrackingEpoch<3>> {
    (0..MAX_SATELLITES as i32)
        .map(|k| {
            let tap = |p: i32| Taps {
                prompt: Iq {
                    i: 40_000 + 100 * k + p,
                    q: -25_000 + 3 * p,
                },
                noise: Iq {
                    i: 9_000 - 50 * k + p,
                    q: 7_000 + p,
                },
                ..Taps::default()
            };
            TrackingEpoch {
                prn: Prn::new(k as u8 + 1).unwrap_or_else(|| panic!("PRN")),
                index: 1000,
                correlations: EpochCorrelations {
                    taps: [tap(0), tap(37), tap(-55)],
                    samples: 2600,
                    first_sample: 2_600_000 + 97 * k as u64,
                    code_phase_at_first: 0,
                    carrier_phase_at_first: 0,
                    complete: true,
                },
                doppler_hz: 1000.0,
                cn0_dbhz: 40.0,
                lock: LockFlags {
                    code: true,
                    phase: true,
                    bit_sync: true,
                },
                state: ChannelState::Tracking,
                phase_error_cycles: 0.0,
                code_error_chips: 0.0,
                data_bit: None,
            }
        })
        .collect()
}

/// `n` satellites spread over the sky, prompt outputs at 40 dB-Hz with a little deterministic
/// "noise" so that the step does real work.
fn observations(n: usize) -> Vec<SatelliteObservation<f32>> {
    let array = AntennaArray::paper_triangle(1.5f32).unwrap_or_else(|e| panic!("{e}"));
    let truth = Paper003Angles::new(0.001, -0.002, 0.0015);
    let model = PhaseModel::new(&array, 0.190_293_7, &truth);
    let amp = 20f32.sqrt() * 40.0;
    (0..n)
        .map(|i| {
            let az = (i as f32) * 0.52;
            let el = 0.15 + 1.3 * (i as f32) / (n as f32);
            let los = [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()];
            let psi = model.phases(&Vector3::from(los));
            let mut prompt = PromptIq::default();
            for p in 0..3 {
                let th = 0.3 * i as f32 + psi[p];
                let wobble = 4.0 * ((i * 3 + p) as f32).sin();
                prompt.i[p] = amp * th.cos() + wobble;
                prompt.q[p] = amp * th.sin() - wobble;
            }
            SatelliteObservation {
                id: i as u8 + 1,
                los,
                prompt,
                noise_var: 1600.0,
                cn0_dbhz: 40.0,
            }
        })
        .collect()
}

fn filter<const N: usize>(
    mode: FilterMode,
    estimate: EstimatedAngles,
    bias: bool,
) -> OneStageFilter<f32, N> {
    let mut config = OneStageConfig::gps_l1(mode, 2.0);
    config.estimate = estimate;
    config.line_bias_states = bias;
    let array = AntennaArray::paper_triangle(1.5).unwrap_or_else(|e| panic!("{e}"));
    let prior = Prior::new(Paper003Angles::new(0.0, 0.0, 0.0), 0.01, 0.001);
    OneStageFilter::new(config, array, &prior).unwrap_or_else(|e| panic!("{e}"))
}

fn bench(c: &mut Criterion) {
    let twelve = observations(MAX_SATELLITES);
    let eight = observations(8);
    let mut full = filter::<8>(
        FilterMode::GaussianApproximation,
        EstimatedAngles::ALL,
        true,
    );
    c.bench_function("one_stage_step_12sat_gaussian_all_states", |b| {
        b.iter(|| black_box(full.step(black_box(&twelve))).ok());
    });
    let mut cg = filter::<8>(FilterMode::ConstantGain, EstimatedAngles::ALL, true);
    c.bench_function("one_stage_step_12sat_constant_gain_all_states", |b| {
        b.iter(|| black_box(cg.step(black_box(&twelve))).ok());
    });
    let mut beta = filter::<2>(
        FilterMode::GaussianApproximation,
        EstimatedAngles::BETA_ONLY,
        false,
    );
    c.bench_function("one_stage_step_8sat_gaussian_beta_only", |b| {
        b.iter(|| black_box(beta.step(black_box(&eight))).ok());
    });
    let mut beta12 = filter::<2>(
        FilterMode::GaussianApproximation,
        EstimatedAngles::BETA_ONLY,
        false,
    );
    c.bench_function("one_stage_step_12sat_gaussian_beta_only", |b| {
        b.iter(|| black_box(beta12.step(black_box(&twelve))).ok());
    });
    let epochs = tracking_epochs();
    let mut adapter =
        ObservationAdapter::new(AdapterConfig::default()).unwrap_or_else(|e| panic!("{e}"));
    let clock = EpochClock::new(2_600_000, 2600).unwrap_or_else(|e| panic!("{e}"));
    for _ in 0..50 {
        for e in &epochs {
            let _ = adapter.observe(e, [0.0, 0.6, 0.8]);
        }
    }
    c.bench_function("one_stage_adapter_12_channels", |b| {
        b.iter(|| {
            let mut n = 0;
            for e in black_box(&epochs) {
                if let (Ok(Some(_)), Some(_)) = (
                    adapter.observe(e, [0.0, 0.6, 0.8]),
                    clock.epoch_of(&e.correlations),
                ) {
                    n += 1;
                }
            }
            black_box(n)
        });
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
