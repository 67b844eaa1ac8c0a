//! Link-time proof that the core's entry points called here contain no reachable panic.
//!
//! The panic handler calls a function that does not exist. If any panic path survives
//! optimization (release, fat LTO), the link fails with an undefined symbol
//! `gnss_attitude_core_can_panic`. The inputs are opaque (`black_box`), so the optimizer cannot
//! prove a path dead by knowing the data; only the code's own checks can remove it.
//! Build: `cargo build --release --bin panic-never`; it is linked, never run. The feature
//! `panic-control` adds a deliberately reachable panic: the link must then fail (`.ci/run`
//! checks both).
#![no_std]
#![no_main]

use core::hint::black_box;
use cortex_m_rt::entry;
use gnss_attitude::ekf::{Ekf, GateConfidence, NisGate};
use gnss_attitude::geometry::{nearest_rotation, Euler321, Paper003Angles, Quaternion};
use gnss_attitude::selftest::run_ekf_self_test;
use gnss_attitude::attitude::array::AntennaArray;
use gnss_attitude::attitude::baseline_epoch::BaselineEpoch;
use gnss_attitude::attitude::dcm_filter::{DcmFilterConfig, DirectionCosineFilter};
use gnss_attitude::attitude::direction_cosine::{ColumnChoice, DirectionCosineModel};
use gnss_attitude::attitude::multi_structure::{fuse, MultiStructureFilter};
use gnss_attitude::attitude::rigid_body::{RigidBodyConfig, RigidBodyFilter};
use gnss_attitude::linalg::singular_values;
use gnss_attitude::gyro::{
    AnchorErrorAndDrift, AttitudePropagator, CalibratorConfig,
    GyroCalibrator, LeastSquaresAccumulator, NormalEquations, PaperCalibrator, PulseDecoder,
    ResidualCentering, ScaleMisalignmentBias, SqrtInformation,
};
use gnss_attitude::attitude::one_stage::{satellite_terms, BesselRatio, PhaseDifferences, FilterMode, OneStageConfig, OneStageFilter, Prior, SatelliteObservation, MAX_SATELLITES};
use gnss_attitude::receiver::{observation_from_epoch, AdapterConfig, AntennaMapping, EpochClock, ObservationAdapter};
use gnss_attitude::frontend::nt1065::{Nt1065, Nt1065Config};
use gnss_attitude::signal::{Correlator, CorrelatorConfig, EpochCorrelations, Iq, Prn, SampleBlock, SampleFormat, Taps};
use gnss_attitude::tracking::acquisition::detection_threshold;
use gnss_attitude::tracking::channel::{refine_frequency, refine_frequency_and_rate};
use gnss_attitude::tracking::{
    Acquisition, AcquisitionConfig, Channel, ChannelConfig, ChannelState, LockFlags, SearchResult, TrackingEpoch,
};
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

extern "C" {
    fn gnss_attitude_core_can_panic() -> !;
}

#[entry]
fn main() -> ! {
    let p0: SMatrix<f32, 6, 6> = black_box(SMatrix::identity());
    if let Ok(mut ekf) = Ekf::<6>::new(black_box(SVector::zeros()), p0) {
        ekf = ekf.with_variance_floor(black_box(1e-9));
        let _ = ekf.predict(&black_box(SMatrix::identity()), &black_box(SMatrix::identity()));
        let _ = ekf.predict_to(&black_box(SVector::zeros()), &black_box(SMatrix::identity()), &black_box(SMatrix::identity()));
        let h: SMatrix<f32, 3, 6> = black_box(SMatrix::zeros());
        let gate = Some(NisGate::chi_square(black_box(3), GateConfidence::P999));
        let _ = ekf.update(&black_box(SVector::<f32, 3>::zeros()), &h, &black_box(SMatrix::identity()), gate);
        let _ = ekf.update_scalar(black_box(0.1), &black_box(SMatrix::<f32, 1, 6>::zeros()), black_box(1.0), gate);
        let _ = ekf.update_sequential(&black_box(SVector::<f32, 3>::zeros()), &h, &black_box(SVector::<f32, 3>::zeros()), gate);
        let _ = ekf.set_covariance(black_box(SMatrix::identity()));
        let _ = ekf.set_state(black_box(SVector::zeros()));
        let _ = black_box(ekf.nees(&black_box(SVector::zeros())));
        let _ = black_box(ekf.std_dev(black_box(7)));
    }
    let m: Matrix3<f32> = black_box(Matrix3::identity());
    let _ = black_box(Quaternion::from_dcm(&m));
    let _ = black_box(Euler321::from_dcm(&m));
    let _ = black_box(Paper003Angles::from_dcm(&m));
    let _ = black_box(nearest_rotation(&m));
    let q = Quaternion::from_rotation_vector(&black_box(nalgebra::Vector3::new(0.1f32, 0.2, 0.3)));
    let _ = black_box(q.to_rotation_vector());
    let _ = black_box(q.normalize());
    let _ = black_box(run_ekf_self_test());
    snapshot_entry_points();
    dcm_entry_points();
    gyro();
    one_stage();
    signal_chain();
    receiver();
    sample_receiver();
    navigation();
    #[cfg(feature = "panic-control")]
    negative_control();
    loop {
        cortex_m::asm::nop();
    }
}

/// Paper 002's entry points with opaque inputs.
#[inline(never)]
fn snapshot_entry_points() {
    use gnss_attitude::attitude::ambiguity::{AmbiguityConfig, AmbiguityResolver, PhaseObservations, PhaseSatellite};
    use gnss_attitude::attitude::paper002::paper_formula;
    use gnss_attitude::attitude::range_model::{BaselineCorrelation, Baselines, RangeDifferences, SatelliteRanges};
    use gnss_attitude::attitude::snapshot::SnapshotSolver;
    use gnss_attitude::attitude::wahba::{solve_wahba, WahbaPair};
    use nalgebra::Vector3;
    let v = |x: f32| black_box(Vector3::new(x, 0.5 * x, 0.25));
    let mut ranges2 = RangeDifferences::<2, 12, f32>::new();
    let mut ranges3 = RangeDifferences::<3, 12, f32>::new();
    let mut phases = PhaseObservations::<2, 12, f32>::new();
    for id in 0..black_box(12u8) {
        let _ = ranges2.push(SatelliteRanges { id, los: v(0.6), range_diff: black_box([0.1, 0.2]), sigma: black_box(0.004) });
        let _ = ranges3.push(SatelliteRanges { id, los: v(0.6), range_diff: black_box([0.1, 0.2, 0.3]), sigma: black_box(0.004) });
        let _ = phases.push(PhaseSatellite { id, los: v(0.6), phase_cycles: black_box([1.1, 2.2]), code_m: black_box([0.1, 0.3]), cofactor: black_box(1.0) });
    }
    if let Ok(b2) = Baselines::new([v(1.0), v(-1.0)]) {
        let corr = BaselineCorrelation::new(black_box(nalgebra::Matrix2::new(1.0, 0.5, 0.5, 1.0))).unwrap_or(BaselineCorrelation::independent());
        let solver = SnapshotSolver::new(b2, corr);
        let _ = black_box(solver.solve(&ranges2));
        if let Ok(r) = AmbiguityResolver::new(solver, black_box(AmbiguityConfig::gps_l1(0.003, 0.3))) {
            let _ = black_box(r.resolve(&phases));
        }
    }
    if let Ok(b3) = Baselines::new([v(1.0), v(-1.0), v(0.3)]) {
        let _ = black_box(paper_formula(&b3, &ranges3));
        let _ = black_box(SnapshotSolver::new(b3, BaselineCorrelation::shared_base_antenna()).solve(&ranges3));
    }
    let pair = WahbaPair { body: v(1.0), reference: v(0.7), weight: black_box(1.0) };
    let _ = black_box(solve_wahba(&[pair, pair]));
}

/// The paper-000 filters with opaque geometry, configuration and measurements.
#[inline(never)]
fn dcm_entry_points() {
    let positions: [nalgebra::Vector3<f32>; 3] = black_box([nalgebra::Vector3::zeros(); 3]);
    let Ok(array) = AntennaArray::new(positions) else {
        return;
    };
    let epoch: BaselineEpoch<f32> = black_box(BaselineEpoch::default());
    let c0: Matrix3<f32> = black_box(Matrix3::identity());
    let r0: SMatrix<f32, 6, 6> = black_box(SMatrix::identity());
    let columns = if black_box(true) { ColumnChoice::Paper } else { ColumnChoice::LargestNormal };
    let config = DcmFilterConfig { columns, ..DcmFilterConfig::paper(black_box(0.01f32), black_box(0.6), black_box(0.1)) };
    if let Ok(model) = DirectionCosineModel::new(&black_box(nalgebra::Vector3::x()), &black_box(nalgebra::Vector3::y()), columns) {
        let y = black_box(SVector::<f32, 6>::zeros());
        let _ = black_box(model.jacobian(&y));
        let _ = black_box(model.jacobian_product(&y));
        let _ = black_box(model.attitude_jacobian(&c0, &y));
        let _ = black_box(model.observation(&y));
        let _ = black_box(model.dcm(&y));
        let _ = black_box(model.state_from_dcm(&c0));
    }
    if let Ok(mut six) = DirectionCosineFilter::new(&array, config, &c0, &r0) {
        let _ = black_box(six.step(&epoch));
        let _ = black_box(six.propagate(&epoch));
        let _ = black_box(six.estimate());
    }
    if let Ok(mut multi) = MultiStructureFilter::new(&array, config, &c0, &r0) {
        if let Ok(m) = multi.step(&epoch) {
            let _ = black_box(fuse(&black_box(m.structures), &black_box([1.0f32, 2.0, 3.0])));
        }
    }
    let rigid_config = RigidBodyConfig {
        dt: black_box(0.01f32),
        sigma_baseline: black_box(0.6),
        sigma_velocity: black_box(0.1),
        gate: black_box(Some(GateConfidence::P999)),
    };
    let q0 = black_box(Quaternion::identity());
    if let Ok(mut rigid) = RigidBodyFilter::new(&array, rigid_config, &q0, &black_box(Matrix3::identity())) {
        let _ = black_box(rigid.step(&epoch));
    }
    let antennas: [Option<nalgebra::Vector3<f32>>; 3] = black_box([None; 3]);
    let _ = black_box(BaselineEpoch::from_antennas(&antennas, &antennas));
}

#[inline(never)]
fn gyro() {
    let config = CalibratorConfig::new(black_box(0.02f32)).with_pulses(
        black_box(2e-5),
        black_box(ResidualCentering::IncrementCorrection),
    );
    let q = Quaternion::new(
        black_box(0.64f32),
        black_box(0.48),
        black_box(0.36),
        black_box(-0.48),
    );
    let theta: Vector3<f32> = black_box(Vector3::new(1e-3, 2e-3, -1e-3));
    if let Ok(mut cal) =
        PaperCalibrator::<SqrtInformation<15>>::paper(config, SqrtInformation::new(), q, q)
    {
        let _ = cal.push_increment(&theta);
        let _ = cal.push_pulses(black_box([3, -7, 100]));
        let _ = cal.set_gyro_correction(black_box(SVector::zeros()));
        let _ = black_box(cal.equations(&q));
        let _ = black_box(cal.add_reference(&q));
        let _ = black_box(cal.add_reference_euler(&Euler321::new(
            black_box(0.1),
            black_box(1.5),
            black_box(-0.2),
        )));
        if let Ok(est) = cal.solve() {
            let _ = black_box(cal.corrected_attitude(&est));
        }
        let _ = black_box(cal.accumulator().marginalize(&black_box([true; 15])));
    }
    type Gnss =
        GyroCalibrator<ScaleMisalignmentBias, AnchorErrorAndDrift, NormalEquations<18>, 9, 6, 18>;
    if let Ok(mut cal) = Gnss::new(
        config,
        ScaleMisalignmentBias,
        AnchorErrorAndDrift,
        NormalEquations::new(),
        q,
        q,
    ) {
        let _ = cal.push_increment(&theta);
        let _ = cal.push_increment(&theta);
        let _ = black_box(cal.add_reference(&q));
        if let Ok(est) = cal.solve() {
            let _ = black_box(cal.corrected_attitude(&est));
        }
    }
    let mut acc = SqrtInformation::<15>::new();
    let _ = acc.add_row(&black_box(SVector::repeat(0.5)), black_box(1.0));
    let _ = black_box(acc.observability(black_box(1e-4)));
    let mut prop = AttitudePropagator::<f32>::new(q);
    if let Ok(p) = prop.as_mut() {
        let _ = black_box(p.push(&theta));
    }
    if let Ok(mut d) = PulseDecoder::new(black_box(1e-5f32), ResidualCentering::MeanResidual) {
        let _ = black_box(d.decode(black_box([1, 2, 3])));
    }
    let _ = black_box(singular_values(
        &black_box(SMatrix::<f32, 6, 6>::identity()),
    ));
}

/// The one-stage filter's entry points on opaque data.
fn one_stage() {
    let v = || black_box(nalgebra::Vector3::new(0.1f32, 0.2, 0.3));
    let _ = black_box(BesselRatio::at(black_box(61.0f32)));
    let z = black_box([nalgebra::Complex::new(1.0f32, 2.0); 3]);
    let _ = black_box(satellite_terms(&z, &v(), black_box(10.0)));
    let Ok(array) = AntennaArray::new([v(), v() * 2.0, v() + nalgebra::Vector3::x()]) else {
        return;
    };
    let prior = match Prior::from_attitude(&black_box(Matrix3::identity()), &black_box(Matrix3::identity()), black_box(0.01)) {
        Ok(p) => p,
        Err(_) => black_box(Prior::new(gnss_attitude::geometry::Paper003Angles::new(0.0, 0.0, 0.0), 0.01, 0.001)),
    };
    let mut config = OneStageConfig::gps_l1(black_box(FilterMode::GaussianApproximation), black_box(2.0));
    config.line_bias_states = black_box(true);
    let config = black_box(config);
    let prior = black_box(prior);
    if let Ok(mut f) = OneStageFilter::<f32, 8>::new(config, black_box(array), &prior) {
        let obs: [SatelliteObservation<f32>; MAX_SATELLITES] = black_box([SatelliteObservation::default(); MAX_SATELLITES]);
        let epoch = obs.get(..black_box(12usize)).unwrap_or(&[]);
        let _ = black_box(f.step(epoch));
        let _ = black_box(f.information(epoch));
        let _ = black_box(f.reinitialize(&prior));
        let _ = black_box(f.reopen_line_biases(black_box(0.25)));
        let _ = black_box((f.angles(), f.rates(), f.line_bias(), f.angle_covariance(), f.lock_status()));
    }
    one_stage_adapter();
    let mut beta = config;
    beta.estimate = black_box(gnss_attitude::attitude::one_stage::EstimatedAngles::BETA_ONLY);
    beta.line_bias_states = black_box(false);
    if let Ok(mut f) = OneStageFilter::<f32, 2>::new(beta, black_box(array), &prior) {
        let obs: [SatelliteObservation<f32>; MAX_SATELLITES] = black_box([SatelliteObservation::default(); MAX_SATELLITES]);
        let epoch = obs.get(..black_box(8usize)).unwrap_or(&[]);
        let _ = black_box(f.step(epoch));
        let _ = black_box(f.angles());
    }
}



/// The adapter from the tracking channels, the epoch grid and the cold start on opaque data.
#[inline(never)]
fn one_stage_adapter() {
    use gnss_attitude::attitude::snapshot::{SnapshotQuality, SnapshotSolution};
    let Some(prn) = Prn::new(black_box(5)) else { return };
    let tap = || Taps {
        early: Iq { i: black_box(1), q: black_box(2) },
        prompt: Iq { i: black_box(3), q: black_box(4) },
        late: Iq { i: black_box(5), q: black_box(6) },
        noise: Iq { i: black_box(7), q: black_box(8) },
    };
    let epoch: TrackingEpoch<3> = black_box(TrackingEpoch {
        prn,
        index: black_box(9),
        correlations: EpochCorrelations {
            taps: [tap(), tap(), tap()],
            samples: black_box(2600),
            first_sample: black_box(1),
            code_phase_at_first: black_box(0),
            carrier_phase_at_first: black_box(0),
            complete: black_box(true),
        },
        doppler_hz: black_box(0.0),
        cn0_dbhz: black_box(40.0),
        lock: black_box(LockFlags::default()),
        state: black_box(ChannelState::Tracking),
        phase_error_cycles: black_box(0.0),
        code_error_chips: black_box(0.0),
        data_bit: black_box(None),
    });
    let los: [f32; 3] = black_box([0.0, 0.6, 0.8]);
    let mapping: AntennaMapping = black_box(AntennaMapping::default());
    let _ = black_box(observation_from_epoch(&epoch, los, black_box([1.0, 2.0, 3.0]), &mapping));
    let config: AdapterConfig = black_box(AdapterConfig { mapping, ..AdapterConfig::default() });
    if let Ok(mut adapter) = ObservationAdapter::new(config) {
        let _ = black_box(adapter.observe(&epoch, los));
        let _ = black_box(adapter.noise().variance(black_box(10)));
        adapter.reset_noise();
    }
    if let Ok(clock) = EpochClock::new(black_box(u64::MAX - 3), black_box(2600)) {
        let _ = black_box(clock.epoch_of(&epoch.correlations));
        let _ = black_box(clock.sample_of(black_box(u64::MAX)));
    }
    let mut d = PhaseDifferences::new();
    let obs: SatelliteObservation<f32> = black_box(SatelliteObservation::default());
    let _ = black_box(d.add(&obs));
    let _ = black_box(d.phase_satellite(black_box(1e-3), black_box(0.01)));
    let solution: SnapshotSolution<f32> = black_box(SnapshotSolution {
        c_rb: Matrix3::identity(),
        q_rb: Quaternion::identity(),
        euler: Euler321::default(),
        covariance: Matrix3::identity(),
        residual_rms: 0.0,
        chi_square: 0.0,
        dof: 1,
        iterations: 1,
        quality: SnapshotQuality::Good,
    });
    let _ = black_box(Prior::from_snapshot(&solution, black_box(0.01)));
}

/// An SPI device whose bus does nothing (the driver's code paths are what is checked).
struct OpaqueSpi;

impl embedded_hal::spi::ErrorType for OpaqueSpi {
    type Error = core::convert::Infallible;
}

impl embedded_hal::spi::SpiDevice for OpaqueSpi {
    fn transaction(&mut self, operations: &mut [embedded_hal::spi::Operation<'_, u8>]) -> Result<(), Self::Error> {
        for op in operations.iter_mut() {
            if let embedded_hal::spi::Operation::TransferInPlace(b) = op {
                for x in b.iter_mut() {
                    *x = black_box(*x);
                }
            }
        }
        Ok(())
    }
}

struct NoDelay;

impl embedded_hal::delay::DelayNs for NoDelay {
    fn delay_ns(&mut self, ns: u32) {
        black_box(ns);
    }
}

/// The signal chain's entry points with opaque inputs.
fn signal_chain() {
    let raw: [u8; 64] = black_box([0u8; 64]);
    let mut i = [0i8; 32];
    let mut q = [0i8; 32];
    let _ = black_box(black_box(SampleFormat::Cs8).decode(&raw, black_box(0), &mut i, &mut q));
    let _ = black_box(black_box(SampleFormat::MultiChannel2 { channels: 3 }).decode(&raw, black_box(2), &mut i, &mut q));
    let cfg = CorrelatorConfig {
        sample_rate_hz: black_box(2.6e6),
        intermediate_frequency_hz: black_box(0.0),
        early_late_offset_chips: black_box(0.5),
        slave_taps: black_box(gnss_attitude::signal::SlaveTaps::Prompt),
    };
    let prn = match Prn::new(black_box(5)) {
        Some(p) => p,
        None => return,
    };
    let si: [i8; 256] = black_box([1; 256]);
    let sq: [i8; 256] = black_box([1; 256]);
    if let Ok(block) = SampleBlock::complex(black_box(0), [&si[..], &si[..], &si[..]], [&sq[..], &sq[..], &sq[..]]) {
        if let Ok(mut c) = Correlator::<3>::new(prn, &cfg) {
            let _ = c.set_carrier_frequency(black_box(1000.0));
            let _ = c.set_code_rate(black_box(1.023e6));
            let _ = c.set_code_phase(black_box(3.0));
            let _ = c.set_carrier_phase(black_box(0.1));
            let mut cursor = black_box(0);
            let _ = black_box(c.run(&block, &mut cursor));
        }
        let mut ch_cfg = ChannelConfig::new(black_box(2.6e6), black_box(0.0));
        ch_cfg.max_doppler_rate_hz_s = black_box(150.0);
        if let Ok(mut ch) = Channel::<3>::new(prn, &ch_cfg) {
            let acq = SearchResult {
                prn,
                detected: true,
                metric: black_box(5.0),
                threshold: black_box(2.0),
                doppler_hz: black_box(100.0),
                code_phase_chips: black_box(10.0),
                first_sample: black_box(0),
            };
            let _ = ch.start(&acq);
            let mut cursor = black_box(0);
            let _ = black_box(ch.process(&block, &mut cursor));
        }
    }
    if let Ok(mut a) = Acquisition::<1024>::new() {
        let cfg = AcquisitionConfig {
            sample_rate_hz: black_box(2.6e6),
            intermediate_frequency_hz: black_box(0.0),
            doppler_max_hz: black_box(0.0),
            doppler_step_hz: black_box(500.0),
            noncoherent_ms: black_box(1),
            false_alarm_probability: black_box(1e-3),
        };
        let _ = black_box(a.search(prn, &si, Some(&sq), black_box(0), &cfg));
    }
    let squares: [[f32; 2]; 8] = black_box([[1.0, 0.0]; 8]);
    let _ = black_box(refine_frequency(&squares, black_box(1e-3)));
    let _ = black_box(refine_frequency_and_rate(&squares, black_box(1e-3), black_box(150.0)));
    let _ = black_box(detection_threshold(black_box(10), black_box(1e5), black_box(1e-3)));
    bitwise(&cfg, prn);
    let mut fe = Nt1065::new(OpaqueSpi);
    let _ = black_box(fe.configure(&black_box(Nt1065Config::three_antenna_l1())));
    let _ = black_box(fe.wait_ready(&mut NoDelay, black_box(10)));
    let _ = black_box(fe.read_register(black_box(44)));
}

/// The bit-parallel correlator's code table (2.6 Msps), at compile time.
static CODE_TABLE: gnss_attitude::signal::bitwise::CodeTable =
    gnss_attitude::signal::bitwise::CodeTable::from_step((1.023e6 / 2.6e6 * 4_294_967_296.0 + 0.5) as u64);

/// The bit-parallel correlator and the packers with opaque inputs (format and carrier levels
/// opaque too, so every kernel variant is linked).
#[inline(never)]
fn bitwise(cfg: &CorrelatorConfig, prn: Prn) {
    use gnss_attitude::signal::bitwise::{
        BitBlock, BitCorrelator, BitCorrelatorConfig, CarrierLevels, PlaneBuffer, PlaneFormat, Resolution,
    };
    let raw: [u8; 96] = black_box([0x5a; 96]);
    let format = PlaneFormat {
        resolution: if black_box(true) { Resolution::TwoBit } else { Resolution::OneBit },
        complex: black_box(true),
    };
    let mut bufs = [PlaneBuffer::<4>::new(format), PlaneBuffer::new(format), PlaneBuffer::new(format)];
    for b in bufs.iter_mut() {
        let _ = black_box(b.pack_bytes(black_box(SampleFormat::SignMagnitude2 { complex: true }), &raw, black_box(0)));
        let _ = black_box(b.pack_bytes(black_box(SampleFormat::MultiChannel2 { channels: 3 }), &raw, black_box(1)));
        let _ = black_box(b.pack_bytes(black_box(SampleFormat::Sign1), &raw, black_box(0)));
        let _ = black_box(b.pack_bytes(black_box(SampleFormat::Sign1Iq), &raw, black_box(0)));
        let _ = black_box(b.pack_bytes(black_box(SampleFormat::SignMagnitude2 { complex: false }), &raw, black_box(0)));
        let _ = black_box(b.pack_bytes(black_box(SampleFormat::Cs8), &raw, black_box(0)));
        let _ = black_box(b.pack_bytes(black_box(SampleFormat::Int8), &raw, black_box(0)));
        let si: [i8; 100] = black_box([3; 100]);
        let _ = black_box(b.pack_i8(&si, &si, black_box(2)));
    }
    let levels = if black_box(true) { CarrierLevels::Three } else { CarrierLevels::Two };
    let config = BitCorrelatorConfig { correlator: *cfg, format, carrier: levels };
    if let (Ok(block), Ok(mut c)) = (
        BitBlock::new(black_box(0), &CODE_TABLE, [bufs[0].planes(), bufs[1].planes(), bufs[2].planes()]),
        BitCorrelator::<3>::new(prn, &config),
    ) {
        let _ = c.set_carrier_frequency(black_box(1000.0));
        let _ = c.set_code_rate(black_box(1.023e6));
        let _ = c.set_code_phase(black_box(3.0));
        let _ = c.set_carrier_phase(black_box(0.1));
        let mut cursor = black_box(0);
        let _ = black_box(c.run(&block, &mut cursor));
    }
}

/// The attitude receiver's entry points with opaque inputs (the configuration too).
#[inline(never)]
fn receiver() {
    use gnss_attitude::attitude::one_stage::{PromptIq, SatelliteObservation};
    use gnss_attitude::receiver::{AttitudeReceiver, GyroConfig, ReceiverConfig, SatelliteAiding};
    let antennas: [[f32; 3]; 3] = black_box([[0.29, 0.0, -0.05], [-0.14, 0.25, -0.05], [-0.14, -0.25, -0.05]]);
    let gyro = black_box(Some(GyroConfig::mems(black_box(0.01), black_box(Some(1e-5)))));
    let config: ReceiverConfig = black_box(ReceiverConfig::gps_l1(antennas, gyro));
    let Ok(mut r) = AttitudeReceiver::new(config) else { return };
    let aiding: [SatelliteAiding; 12] = core::array::from_fn(|i| SatelliteAiding {
        prn: black_box(i as u8 + 1),
        epoch: black_box(0),
        los: black_box([0.0, 0.6, -0.8]),
        los_rate: black_box([1e-4, 0.0, 0.0]),
    });
    let aiding: &[SatelliteAiding] = black_box(&aiding[..]);
    let _ = black_box(r.set_aiding(aiding));
    for k in 0..black_box(3u64) {
        let epoch = black_box(k);
        let _ = black_box(r.push_gyro_increment(&black_box([1e-4, 2e-4, -1e-4])));
        let _ = black_box(r.push_gyro_pulses(black_box([3, -2, 10])));
        for i in 0..black_box(12u8) {
            let obs: SatelliteObservation<f32> = black_box(SatelliteObservation {
                id: black_box(i.wrapping_add(1)),
                los: black_box([0.0, 0.0, 1.0]),
                prompt: PromptIq { i: black_box([30.0, 20.0, -10.0]), q: black_box([1.0, 15.0, 8.0]) },
                noise_var: black_box(1.0),
                cn0_dbhz: black_box(45.0),
            });
            let _ = black_box(r.push_observation(epoch, &obs));
        }
        r.close_through(black_box(epoch));
    }
    receiver_outputs(&mut r);
}

/// Every output of the receiver.
#[inline(never)]
fn receiver_outputs(r: &mut gnss_attitude::receiver::AttitudeReceiver) {
    let _ = black_box(r.config());
    let _ = black_box(r.attitude());
    let _ = black_box(r.fine_estimate());
    let _ = black_box(r.snapshot_estimate());
    let _ = black_box(r.rigid_body_estimate());
    let _ = black_box(r.gyro_bias());
    let _ = black_box(r.gyro_bias_sigma());
    let _ = black_box(r.gyro_calibration());
    let _ = black_box(r.last_integrity_check());
    let _ = black_box(r.health());
    let _ = black_box(r.events_dropped());
    let _ = black_box(r.epoch());
    while let Some(e) = r.pop_event() {
        let _ = black_box(e.epoch());
        let _ = black_box(e);
    }
}

/// The receiver from raw samples at the size host-sim flies (12 channels, 2048-point
/// acquisition): search, start, push samples, release; every configuration opaque.
#[inline(never)]
fn sample_receiver() {
    use gnss_attitude::receiver::{GyroConfig, ReceiverConfig, SampleFrontConfig, SampleReceiver};
    let antennas: [[f32; 3]; 3] = black_box([[0.29, 0.0, -0.05], [-0.14, 0.25, -0.05], [-0.14, -0.25, -0.05]]);
    let gyro = black_box(Some(GyroConfig::mems(black_box(0.01), black_box(None))));
    let config: ReceiverConfig = black_box(ReceiverConfig::gps_l1(antennas, gyro));
    let front: SampleFrontConfig = black_box(SampleFrontConfig::leo_complex(black_box(2.6e6)));
    let Ok(mut rx) = SampleReceiver::<12, 2048>::new(config, front) else { return };
    let Some(prn) = Prn::new(black_box(9)) else { return };
    // the slices opaque, their lengths too
    let (si, sq) = ([1i8; 2600], [-1i8; 2600]);
    let si: &[i8] = black_box(&si[..]);
    let sq: &[i8] = black_box(&sq[..]);
    let q = if black_box(true) { Some(sq) } else { None };
    let _ = black_box(rx.search(prn, si, q, black_box(0)));
    // the search on bit planes, collected block by block (format and lengths opaque)
    {
        use gnss_attitude::signal::bitwise::{PlaneBuffer, PlaneFormat, Resolution};
        use gnss_attitude::tracking::SearchSamples;
        let format = PlaneFormat {
            resolution: if black_box(true) { Resolution::TwoBit } else { Resolution::OneBit },
            complex: black_box(true),
        };
        let mut block = PlaneBuffer::<82>::new(format);
        let mut collected = PlaneBuffer::<164>::new(format);
        for _ in 0..black_box(3) {
            let _ = black_box(block.pack_i8(si, sq, black_box(2)));
            let _ = black_box(collected.append(&block.planes()));
        }
        let samples = if black_box(true) { Ok(SearchSamples::Planes(collected.planes().head(black_box(5000)))) } else { SearchSamples::decoded(si, q) };
        if let Ok(samples) = samples {
            let _ = black_box(rx.search_samples(prn, black_box(samples), black_box(0)));
        }
        collected.clear();
    }
    let acq: SearchResult = black_box(SearchResult {
        prn,
        detected: true,
        metric: black_box(5.0),
        threshold: black_box(2.0),
        doppler_hz: black_box(100.0),
        code_phase_chips: black_box(10.0),
        first_sample: black_box(0),
    });
    let _ = black_box(rx.start(&acq));
    let _ = black_box(rx.tracks(prn));
    rx.set_deferred_checks(black_box(true));
    for first in [black_box(0u64), black_box(2600)] {
        if let Ok(block) = SampleBlock::complex(first, [si, si, si], [sq, sq, sq]) {
            let _ = black_box(rx.push_samples(black_box(&block)));
        }
        if black_box(true) {
            let _ = black_box(rx.run_deferred());
        }
    }
    rx.set_deferred_checks(black_box(false));
    let _ = black_box(rx.check_overruns());
    for c in rx.channels() {
        let _ = black_box(c);
    }
    let _ = black_box(rx.attitude());
    let _ = black_box(rx.receiver().attitude());
    receiver_outputs(rx.receiver_mut());
    let _ = black_box(rx.release(prn));
}

/// Navigation: the channel decoder, the store, the fix, the LEO filter, the lines of sight.
#[inline(never)]
fn navigation() {
    use gnss_attitude::nav::bits::BitSyncConfig;
    use gnss_attitude::nav::example;
    use gnss_attitude::nav::{
        line_of_sight, solve, ChannelDecoder, GpsTime, NavigationStore, Observation, OrbitFilter,
        OrbitFilterConfig, ReferenceFrame, SolverConfig,
    };
    let mut dec = ChannelDecoder::new(black_box(5), BitSyncConfig::default());
    let mut store = NavigationStore::default();
    for k in 0..black_box(4000u64) {
        if let Ok(Some(sf)) = dec.push_prompt(black_box(k), black_box(1.0)) {
            let _ = black_box(store.add_subframe(black_box(5), &sf));
        }
        if let Err(gnss_attitude::nav::decoder::DecodeError::Subframe(e)) = dec.push_prompt(black_box(k), black_box(-1.0)) {
            store.record_decode_error(&e);
        }
    }
    let _ = black_box(dec.transmit_time(black_box(5000), black_box(100.0)));
    let ephs = black_box(example::constellation());
    let t = GpsTime { week: black_box(2195), tow_s: black_box(238_000.0) };
    let obs: [Observation; 8] = core::array::from_fn(|i| Observation {
        prn: black_box(i as u8 + 1),
        transmit: t,
        pseudorange_m: black_box(2.1e7),
        doppler_hz: Some(black_box(100.0)),
        sigma_m: black_box(3.0),
    });
    let iono = example::EXAMPLE_KLOBUCHAR;
    if let Ok(fix) = solve(&obs, &ephs[..], Some(&iono), &t, None, &black_box(SolverConfig::ground())) {
        if let Ok(mut f) = OrbitFilter::from_fix(&fix, OrbitFilterConfig::default()) {
            let _ = black_box(f.predict_to(&black_box(t)));
            let _ = black_box(f.update(&fix));
            for e in ephs.iter() {
                let _ = black_box(line_of_sight(&f.state(), e, &ReferenceFrame::LocalNed));
                let _ = black_box(line_of_sight(&f.state(), e, &ReferenceFrame::Inertial { epoch: t }));
            }
        }
    }
    let _ = black_box(solve(&obs, &store, None, &t, None, &black_box(SolverConfig::leo())));
}

/// The negative control (feature `panic-control`): a deliberately reachable panic, a slice
/// indexed with an opaque index. With it this binary must fail to link; `.ci/run` checks
/// that it does, so a proof that links is known to be able to fail.
#[cfg(feature = "panic-control")]
#[inline(never)]
fn negative_control() {
    let data: [u8; 4] = black_box([1, 2, 3, 4]);
    let _ = black_box(data[black_box(7usize)]);
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    // SAFETY: never called if the proof holds; the symbol does not exist, so a surviving panic
    // path fails the link.
    unsafe { gnss_attitude_core_can_panic() }
}
