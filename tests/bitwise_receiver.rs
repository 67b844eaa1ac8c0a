//! The whole receiver from bit planes: a `SampleReceiver` whose channels run the bit-parallel
//! correlator, fed the three antennas' 2-bit sign/magnitude bytes (`sm2iq`, complex) packed
//! straight into planes (2-bit, and 1-bit: the sign planes of the same bytes), searches on the
//! reference antenna's planes unpacked to `i8`, tracks the example flight's eight satellites
//! and reaches a fine attitude within a fraction of a degree of the truth.
//!
//! The scene is the core's example flight (`receiver::example`: its sky, antennas, attitude
//! and body rate) synthesized as samples at 2.6 Msps, 45 dB-Hz; the receiver gets the flight's
//! aiding (lines of sight) and nothing else.

use gnss_attitude::receiver::example::{antennas, ExampleFlight, BODY_RATE, CN0_DBHZ};
use gnss_attitude::receiver::{AttitudeSource, SampleFrontConfig, SampleReceiver};
use gnss_attitude::signal::bitwise::{
    BitBlock, BitCorrelator, CarrierLevels, CodeTable, PlaneBuffer, PlaneFormat, Resolution,
};
use gnss_attitude::signal::{BitSettings, Prn, SampleFormat};
use gnss_attitude::tracking::SearchSamples;
use host_sim::synth::quantize::encode;
use host_sim::synth::{AttitudeMotion, FrontEnd, Satellite, Scene};
use nalgebra::{Matrix3, Vector3};

const FS: f64 = 2.6e6;
/// Samples per receiver epoch (1 ms).
const EPOCH: usize = 2600;
/// Samples per block (0.1 s).
const BLOCK: usize = 100 * EPOCH;
/// Plane words per block.
const WORDS: usize = BLOCK.div_ceil(32);

type BitFront = SampleReceiver<8, 2048, BitCorrelator<3>>;

/// The example flight as a sample-level scene.
fn scene(seed: u64) -> Scene {
    let flight = ExampleFlight::new(seed);
    let aiding = flight.aiding(0);
    let satellites = aiding
        .iter()
        .enumerate()
        .map(|(k, a)| Satellite {
            prn: a.prn,
            cn0_dbhz: f64::from(CN0_DBHZ),
            doppler_hz: -3500.0 + 930.0 * k as f64,
            doppler_rate_hz_s: 0.3 * (k as f64 - 3.5),
            code_phase_chips: (137.0 + 211.7 * k as f64) % 1023.0,
            carrier_phase_cycles: 0.13 * k as f64,
            los_ref: ExampleFlight::los(k).cast::<f64>(),
            data_seed: Some(seed + k as u64),
            track: None,
        })
        .collect();
    let dcm = flight.q0.to_dcm();
    let c_rb0 = Matrix3::from_fn(|r, c| f64::from(dcm[(r, c)]));
    Scene {
        satellites,
        antennas_b: antennas()
            .iter()
            .map(|p| Vector3::from(*p).cast::<f64>())
            .collect(),
        line_bias_cycles: vec![0.0, 0.11, -0.19],
        attitude: AttitudeMotion::ConstantRate {
            c_rb0,
            omega_b: Vector3::from(BODY_RATE).cast::<f64>(),
        },
        front_end: FrontEnd {
            sample_rate_hz: FS,
            intermediate_frequency_hz: 0.0,
            complex: true,
        },
        noise_seed: Some(seed ^ 0x0b17_b17b),
    }
}

/// Runs `seconds` of the scene through a bit-plane receiver with `settings`; returns the
/// attitude error at the end (degrees) and the source.
fn fly(settings: BitSettings, seconds: f64) -> (AttitudeSource, f64, usize) {
    let sc = scene(5);
    let flight = ExampleFlight::new(5);
    let mut front = SampleFrontConfig::leo_complex(FS);
    front.acquisition.doppler_max_hz = 5000.0;
    front.acquisition.noncoherent_ms = 10;
    let mut rx =
        Box::new(BitFront::with_settings(ExampleFlight::config(false), front, settings).unwrap());
    let table = CodeTable::new(FS).unwrap();
    let sm2iq = SampleFormat::SignMagnitude2 { complex: true };
    let needed = front.acquisition.samples_needed();
    let mut planes: Vec<Box<PlaneBuffer<WORDS>>> = (0..3)
        .map(|_| Box::new(PlaneBuffer::new(settings.format)))
        .collect();
    let blocks = (seconds * FS / BLOCK as f64).ceil() as u64;
    let mut observations = 0;
    for b in 0..blocks {
        let first = b * BLOCK as u64;
        let bytes = encode(sm2iq, &sc.synthesize(first, BLOCK)).unwrap();
        for (p, bytes) in planes.iter_mut().zip(&bytes) {
            assert_eq!(p.pack_bytes(sm2iq, bytes, 0).unwrap(), BLOCK);
        }
        // Searches on the first block: the reference antenna's planes as they are.
        if b == 0 {
            let reference = SearchSamples::Planes(planes[0].planes().head(needed));
            assert_eq!(reference.len(), needed);
            for a in flight.aiding(0) {
                let r = rx
                    .search_samples(Prn::new(a.prn).unwrap(), reference, first)
                    .unwrap();
                assert!(r.detected, "PRN {} not detected", a.prn);
            }
        }
        let block = BitBlock::new(
            first,
            &table,
            [planes[0].planes(), planes[1].planes(), planes[2].planes()],
        )
        .unwrap();
        // The aiding a flight computer gives, every 100 epochs (every block).
        let k = first / EPOCH as u64;
        rx.receiver_mut().set_aiding(&flight.aiding(k)).unwrap();
        let report = rx.push_samples(&block).unwrap();
        observations += report.observations as usize;
    }
    let att = rx.attitude();
    let err = f64::from(att.q_rb.angle_to(&flight.attitude(att.epoch)).to_degrees());
    (att.source, err, observations)
}

#[test]
fn a_bit_plane_receiver_reaches_fine_attitude() {
    for (resolution, carrier) in [
        (Resolution::TwoBit, CarrierLevels::Three),
        (Resolution::OneBit, CarrierLevels::Two),
    ] {
        let settings = BitSettings {
            format: PlaneFormat {
                resolution,
                complex: true,
            },
            carrier,
        };
        let (source, err, observations) = fly(settings, 4.0);
        eprintln!("{resolution:?} {carrier:?}: {source:?}, attitude error {err:.6}°, {observations} observations");
        assert_eq!(source, AttitudeSource::Fine);
        assert!(err < 0.5, "{err}°");
    }
}

/// Existing callers compile unchanged (`SampleReceiver::<S, N>::new` is the `i8` receiver), and
/// the bit-plane receiver refuses what its correlator cannot run: one sample per chip (the `i8`
/// correlator takes it; the bit-parallel one needs two), the refusal keeping its cause.
#[test]
fn the_i8_receiver_stays_the_default_and_the_bit_receiver_refuses_its_own_limits() {
    use gnss_attitude::receiver::{ConfigError, ReceiverError};
    use gnss_attitude::signal::bitwise::BitCorrelatorError;
    use gnss_attitude::signal::Correlator;
    use gnss_attitude::tracking::TrackingError;
    let slow = SampleFrontConfig::leo_complex(1.023e6);
    let i8_rx: SampleReceiver<2, 1024, Correlator<3>> =
        SampleReceiver::<2, 1024>::new(ExampleFlight::config(false), slow).unwrap();
    assert_eq!(i8_rx.channels().count(), 0);
    let settings = BitSettings {
        format: PlaneFormat {
            resolution: Resolution::OneBit,
            complex: true,
        },
        carrier: CarrierLevels::Two,
    };
    let refused = SampleReceiver::<2, 1024, BitCorrelator<3>>::with_settings(
        ExampleFlight::config(false),
        slow,
        settings,
    )
    .err();
    assert_eq!(
        refused,
        Some(ReceiverError::InvalidConfig(ConfigError::Tracking(
            TrackingError::Bitwise(BitCorrelatorError::InvalidConfig)
        )))
    );
}
