//! Paper 003's filter fed from samples: three-antenna samples synthesized by host-sim (its own
//! signal model, f64 truth) → the core's acquisition, fixed-point correlators and tracking
//! channels → the core's adapter (`ObservationAdapter`, `EpochClock`) → the one-stage filter.
//!
//! * The adapter's conventions: with a known attitude (all three angles non-zero) and known
//!   line biases, the inter-antenna phases of the adapted observations are the ones the
//!   filter's phase model predicts (antenna order, sign of Q, per-antenna scale).
//! * The sample-level path tracks at the loop-limited bound and delivers the information of
//!   the I/Q fast path (the fixed-point chain's loss, measured on the discriminator).
//! * A cold start: the averaged phases solved by the snapshot solver's ambiguity resolver,
//!   `Prior::from_snapshot`, and the filter pulls in on the samples.

use std::f64::consts::TAU;

use gnss_attitude::attitude::ambiguity::{
    AmbiguityConfig, AmbiguityResolver, PhaseObservations, PhaseSatellite,
};
use gnss_attitude::attitude::array::{Antenna, AntennaArray};
use gnss_attitude::attitude::one_stage::{
    EstimatedAngles, FilterMode, LockStatus, OneStageConfig, OneStageFilter, PhaseDifferences,
    PhaseModel, Prior, SatelliteObservation,
};
use gnss_attitude::attitude::range_model::{BaselineCorrelation, Baselines};
use gnss_attitude::attitude::snapshot::SnapshotSolver;
use gnss_attitude::geometry::{log_so3, Paper003Angles};
use gnss_attitude::receiver::{
    AdapterConfig, AntennaMapping, EpochClock, ObservationAdapter, QuadratureSign,
};
use host_sim::chain::{ChainParams, Tracker};
use host_sim::scenarios::one_stage::loss;
use host_sim::scenarios::one_stage::samples::{
    chain_params, record, record_source, SAMPLES_PER_EPOCH, SAMPLE_RATE_HZ,
};
use host_sim::scenarios::one_stage::sim::{simulate_with, InputPath, RunConfig};
use host_sim::scenarios::one_stage::source::{IqFastPath, EPOCH_S};
use host_sim::scenarios::one_stage::truth::{sky_g1, SIDE_M, WAVELENGTH_M};
use host_sim::synth::AttitudeMotion;
use nalgebra::{Complex, Matrix3, Vector3};

/// The attitude of the convention test: every angle of eq. (2) non-zero.
fn truth_angles() -> Paper003Angles<f64> {
    Paper003Angles::new(0.3, -0.4, 1.1)
}

/// Line biases of A, B, C, cycles.
const BIAS_CYCLES: [f64; 3] = [0.0, 0.13, -0.27];

/// The scenario's chain at `cn0` with the body at `angles` and the given line biases; the
/// scene's antennas are the core array's positions (the one `AntennaArray` type).
fn scene_at(
    angles: &Paper003Angles<f64>,
    cn0: f64,
    bias_cycles: [f64; 3],
    seed: u64,
) -> ChainParams {
    let mut p = chain_params(&RunConfig::paper(FilterMode::GaussianApproximation), seed);
    let array = AntennaArray::<f64>::paper_triangle(SIDE_M).unwrap();
    p.scene.antennas_b = array.positions().to_vec();
    p.scene.attitude = AttitudeMotion::Constant(angles.to_dcm());
    p.scene.line_bias_cycles = bias_cycles.to_vec();
    for s in &mut p.scene.satellites {
        s.cn0_dbhz = cn0;
    }
    p
}

/// Tracks `params` for `seconds` and returns the adapted observations (with their filter
/// epoch on a 1 ms grid from `from_s`) of the epochs after `from_s`.
fn adapted(
    params: &ChainParams,
    seconds: f64,
    from_s: f64,
    mapping: AntennaMapping,
) -> Vec<(u64, SatelliteObservation<f32>)> {
    let mut tracker = Tracker::acquire(params).unwrap();
    assert_eq!(
        tracker.channels.len(),
        params.scene.satellites.len(),
        "all acquired"
    );
    let los: Vec<[f32; 3]> = tracker
        .channels
        .iter()
        .map(|c| {
            params.scene.satellites[c.scene_index]
                .los_ref
                .map(|v| v as f32)
                .into()
        })
        .collect();
    let config = AdapterConfig {
        mapping,
        ..AdapterConfig::default()
    };
    let mut adapter = ObservationAdapter::new(config).unwrap();
    let clock = EpochClock::new((from_s * SAMPLE_RATE_HZ) as u64, SAMPLES_PER_EPOCH).unwrap();
    let total = (seconds * SAMPLE_RATE_HZ) as u64;
    let mut out = Vec::new();
    let mut first = 0;
    while first < total {
        let epochs = tracker.track(params, first, 32_768).unwrap();
        first += 32_768;
        for (es, l) in epochs.iter().zip(&los) {
            for e in es {
                if let Some(o) = adapter.observe(e, *l).unwrap() {
                    if let Some(k) = clock.epoch_of(&e.correlations) {
                        out.push((k, o));
                    }
                }
            }
        }
    }
    out
}

fn wrap(x: f64) -> f64 {
    (x + std::f64::consts::PI).rem_euclid(TAU) - std::f64::consts::PI
}

/// Per satellite: measured `arg Σ z_P z_A*` minus the phase model's `ψ_P − ψ_A` and the line
/// biases, P = B, C (rad); the mean `|z|²` of each antenna and the mean reported C/N0.
fn phase_residuals(obs: &[(u64, SatelliteObservation<f32>)]) -> Vec<(u8, [f64; 2], [f64; 3], f64)> {
    let array = AntennaArray::<f64>::paper_triangle(SIDE_M).unwrap();
    let model = PhaseModel::new(&array, WAVELENGTH_M, &truth_angles());
    let mut ids: Vec<u8> = obs.iter().map(|(_, o)| o.id).collect();
    ids.sort_unstable();
    ids.dedup();
    ids.into_iter()
        .map(|id| {
            let mine: Vec<_> = obs.iter().filter(|(_, o)| o.id == id).collect();
            let los = Vector3::from(mine[0].1.los.map(f64::from));
            let psi = model.phases(&los);
            let z = |o: &SatelliteObservation<f32>, p: usize| {
                Complex::new(f64::from(o.prompt.i[p]), f64::from(o.prompt.q[p]))
            };
            let mut sums = [Complex::new(0.0, 0.0); 2];
            let mut power = [0.0; 3];
            let mut cn0 = 0.0;
            for (_, o) in &mine {
                cn0 += f64::from(o.cn0_dbhz) / mine.len() as f64;
                sums[0] += z(o, 1) * z(o, 0).conj();
                sums[1] += z(o, 2) * z(o, 0).conj();
                for (p, w) in power.iter_mut().enumerate() {
                    *w += z(o, p).norm_sqr() / mine.len() as f64;
                }
            }
            let res = [1, 2].map(|p| {
                let predicted = psi[p] - psi[0] + TAU * (BIAS_CYCLES[p] - BIAS_CYCLES[0]);
                wrap(sums[p - 1].arg() - predicted)
            });
            (id, res, power, cn0)
        })
        .collect()
}

#[test]
fn adapted_samples_have_the_inter_antenna_phases_of_the_filters_phase_model() {
    // 5 satellites at 45 dB-Hz (q_T = 31.6: 0.18 rad per epoch and antenna pair), 0.6 s
    // averaged after lock: each mean phase difference is good to ~0.01 rad
    let mut params = scene_at(&truth_angles(), 45.0, BIAS_CYCLES, 7);
    params.scene.satellites.truncate(5);
    params.search_prns.truncate(5);
    let obs = adapted(&params, 1.6, 1.0, AntennaMapping::default());
    let per_sat = phase_residuals(&obs);
    assert_eq!(per_sat.len(), 5);
    for (id, res, power, cn0) in &per_sat {
        for r in res {
            assert!(r.abs() < 0.04, "PRN {id}: phase residual {r:.4} rad");
        }
        // noise units: E|z|² = 2 + 2 q_T on every antenna (each divided by its own noise σ);
        // q_T is the thermal 45 dB-Hz less the other four satellites' cross-correlation,
        // (n − 1) q_T / 1023 = 12 % of the noise at most, which the noise tap sees too
        let q_t = 10f64.powf(4.5) * EPOCH_S;
        for w in power {
            let snr = (w - 2.0) / 2.0 / q_t;
            assert!(
                (0.84..1.02).contains(&snr),
                "PRN {id}: SNR / thermal {snr:.3}"
            );
        }
        assert!((cn0 - 45.0).abs() < 1.0, "PRN {id}: reported C/N0 {cn0:.2}");
    }
    // the same samples with the other sign of Q, or B and C swapped, do not fit the model
    for wrong in [
        AntennaMapping {
            quadrature: QuadratureSign::Conjugate,
            ..AntennaMapping::default()
        },
        AntennaMapping {
            inputs: [0, 2, 1],
            ..AntennaMapping::default()
        },
    ] {
        let obs = adapted(&params, 1.2, 1.0, wrong);
        let worst = phase_residuals(&obs)
            .iter()
            .flat_map(|(_, r, _, _)| r.map(f64::abs))
            .fold(0.0, f64::max);
        assert!(worst > 0.5, "{wrong:?}: worst residual only {worst:.3} rad");
    }
}

#[test]
fn the_sample_level_path_tracks_at_the_bound_and_delivers_the_information_of_the_iq_path() {
    let cfg = RunConfig {
        duration_s: 4.0,
        input: InputPath::SampleLevel,
        ..RunConfig::paper(FilterMode::GaussianApproximation)
    };
    let rec =
        std::sync::Arc::new(record(&cfg, 3, host_sim::synth::quantize::Quantizer::I8).unwrap());
    assert_eq!(rec.stats.tracked, 8);
    assert_eq!(rec.stats.late, 0);
    assert_eq!(
        rec.stats.empty_epochs, 0,
        "all channels tracking after the warm-up"
    );
    // the information per epoch (3000 epochs: ±0.1 dB) matches the I/Q fast path's
    let sky = sky_g1(cfg.satellites);
    let iq_epochs = record_source(&cfg, &mut IqFastPath::new(&sky, 40.0, [0.0; 3], 3)).unwrap();
    let (ls, li) = (
        loss::measure(&cfg, &rec.epochs).unwrap(),
        loss::measure(&cfg, &iq_epochs).unwrap(),
    );
    let chain_db = ls.loss_db - li.loss_db;
    assert!(
        (-0.3..0.5).contains(&chain_db),
        "chain loss {chain_db:.2} dB (samples {:.2}, I/Q {:.2})",
        ls.loss_db,
        li.loss_db
    );
    // and the filter on it: at the bound within the noise of 3 s (about 12 loop time
    // constants), locked, both forms
    for mode in [FilterMode::GaussianApproximation, FilterMode::ConstantGain] {
        let c = RunConfig { mode, ..cfg };
        let r = simulate_with(
            &c,
            Box::new(host_sim::scenarios::one_stage::samples::Replay::new(
                rec.clone(),
            )),
        )
        .unwrap();
        let bound = c.bound_arcmin();
        assert!(
            r.rms_arcmin < 1.5 * bound && r.rms_arcmin > 0.5 * bound,
            "{mode:?}: {:.3}′ vs bound {bound:.3}′",
            r.rms_arcmin
        );
        assert_eq!(r.final_status, LockStatus::Locked);
        assert!(r.flagged_at_s.is_none());
    }
}

#[test]
fn a_cold_start_from_the_snapshot_solver_pulls_in_on_samples() {
    let angles = Paper003Angles::new(0.05, 0.35, -0.8);
    let params = scene_at(&angles, 45.0, [0.0; 3], 11);
    let obs = adapted(&params, 2.0, 1.0, AntennaMapping::default());
    // 1. the phases of the first 200 ms, one PhaseDifferences per satellite
    let mut avg: Vec<(u8, PhaseDifferences)> = Vec::new();
    for (_, o) in obs.iter().filter(|(k, _)| *k < 200) {
        match avg.iter_mut().find(|(id, _)| *id == o.id) {
            Some((_, d)) => d.add(o).unwrap(),
            None => {
                let mut d = PhaseDifferences::new();
                d.add(o).unwrap();
                avg.push((o.id, d));
            }
        }
    }
    let avg: Vec<PhaseDifferences> = avg.into_iter().map(|(_, d)| d).collect();
    assert_eq!(avg.len(), 8);
    let sigma_cycles = avg[0].sigma_cycles(1e-3).unwrap();
    let mut phases = PhaseObservations::<2, 12, f64>::new();
    for d in &avg {
        let s = d.phase_satellite(1e-3, sigma_cycles).unwrap();
        phases
            .push(PhaseSatellite {
                id: s.id,
                los: s.los.cast(),
                phase_cycles: s.phase_cycles.map(f64::from),
                code_m: [0.0; 2],
                cofactor: f64::from(s.cofactor),
            })
            .unwrap();
    }
    // 2. the snapshot solver (f64: with no code single differences — one code NCO for all
    // antennas — the code σ must exceed the baselines, and the float covariance, 10⁷ times
    // wider along the code directions, is too ill-conditioned for f32): baselines A→B, A→C
    // from the one array type, SDs sharing A
    let array = AntennaArray::<f64>::paper_triangle(SIDE_M).unwrap();
    let a = array.position(Antenna::A);
    let baselines = Baselines::new([
        array.position(Antenna::B) - a,
        array.position(Antenna::C) - a,
    ])
    .unwrap();
    let solver = SnapshotSolver::new(baselines, BaselineCorrelation::shared_base_antenna());
    // the SD noise: thermal (σ above) and the other satellites' cross-correlation
    let phase_sigma_m = 2.0 * f64::from(sigma_cycles) * WAVELENGTH_M;
    let resolver =
        AmbiguityResolver::new(solver, AmbiguityConfig::gps_l1(phase_sigma_m, 3.0)).unwrap();
    let fix = resolver.resolve(&phases).expect("ambiguities fixed");
    let c_true: Matrix3<f64> = angles.to_dcm();
    let snapshot_err = log_so3(&(fix.solution.c_rb.transpose() * c_true))
        .unwrap()
        .norm();
    assert!(
        snapshot_err < 0.01,
        "snapshot error {:.3}°",
        snapshot_err.to_degrees()
    );
    // 3. the prior from it, then the three-angle filter on the rest of the samples
    let prior = Prior::from_snapshot(&fix.solution, 0.005).unwrap();
    let mut config = OneStageConfig::<f64>::gps_l1(FilterMode::GaussianApproximation, 2.0);
    config.wavelength_m = WAVELENGTH_M;
    config.estimate = EstimatedAngles::ALL;
    let mut filter = OneStageFilter::<f64, 6>::new(config, array, &prior).unwrap();
    let last = obs.iter().map(|(k, _)| *k).max().unwrap();
    let mut epoch = Vec::new();
    let mut status = LockStatus::PullIn;
    for k in 200..=last {
        epoch.clear();
        epoch.extend(obs.iter().filter(|(j, _)| *j == k).map(|(_, o)| o.to_f64()));
        status = filter.step(&epoch).unwrap().status;
    }
    assert_eq!(status, LockStatus::Locked);
    let err = log_so3(&(filter.attitude().transpose() * c_true))
        .unwrap()
        .norm();
    assert!(
        err < 3f64.to_radians() / 60.0,
        "one-stage attitude error {:.2}′ after 0.8 s",
        err.to_degrees() * 60.0
    );
}
