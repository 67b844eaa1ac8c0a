//! Tests of the tracking-epoch adapter on hand-made epochs (the conventions on synthesized
//! samples are tested in the crate's `tests/one_stage_samples.rs`).

use super::adapter::*;
use crate::attitude::one_stage::OneStageError;
use crate::signal::correlator::{EpochCorrelations, Iq, Taps};
use crate::signal::Prn;
use crate::tracking::{ChannelState, LockFlags, TrackingEpoch};

fn tap(i: i32, q: i32) -> Iq {
    Iq { i, q }
}

fn epoch(prompts: [(i32, i32); 3], noise: [(i32, i32); 3]) -> TrackingEpoch<3> {
    let taps = core::array::from_fn(|k| Taps {
        prompt: tap(prompts[k].0, prompts[k].1),
        noise: tap(noise[k].0, noise[k].1),
        ..Taps::default()
    });
    TrackingEpoch {
        prn: Prn::new(7).unwrap(),
        index: 500,
        correlations: EpochCorrelations {
            taps,
            samples: 2600,
            first_sample: 10_000,
            code_phase_at_first: 0,
            carrier_phase_at_first: 0,
            complete: true,
        },
        doppler_hz: 1000.0,
        cn0_dbhz: 41.0,
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
}

const UP: [f32; 3] = [0.0, 0.0, 1.0];

fn close(a: [f32; 3], b: [f32; 3]) {
    for (x, y) in a.iter().zip(b.iter()) {
        assert!((x - y).abs() < 1e-4, "{a:?} vs {b:?}");
    }
}

#[test]
fn prompts_are_mapped_sign_fixed_and_divided_by_their_own_noise() {
    let e = epoch([(1000, 0), (0, 2000), (-3000, 0)], [(0, 0); 3]);
    let var = [100.0, 400.0, 900.0];
    let o = observation_from_epoch(&e, UP, var, &AntennaMapping::default()).unwrap();
    assert_eq!(o.id, 7);
    assert_eq!(o.noise_var, 1.0);
    assert_eq!(o.cn0_dbhz, 41.0);
    close(o.prompt.i, [100.0, 0.0, -100.0]);
    close(o.prompt.q, [0.0, 100.0, 0.0]);
    let conj = AntennaMapping {
        quadrature: QuadratureSign::Conjugate,
        ..AntennaMapping::default()
    };
    let o = observation_from_epoch(&e, UP, var, &conj).unwrap();
    close(o.prompt.q, [0.0, -100.0, 0.0]);
    // A on input 2, B on input 0, C on input 1
    let swapped = AntennaMapping {
        inputs: [2, 0, 1],
        ..AntennaMapping::default()
    };
    let o = observation_from_epoch(&e, UP, var, &swapped).unwrap();
    close(o.prompt.i, [-100.0, 100.0, 0.0]);
    close(o.prompt.q, [0.0, 0.0, 100.0]);
}

#[test]
fn unusable_epochs_are_typed_errors() {
    let e = epoch([(1, 1); 3], [(0, 0); 3]);
    let m = AntennaMapping::default();
    let var = [1.0; 3];
    let bad_map = AntennaMapping {
        inputs: [0, 0, 1],
        ..m
    };
    assert_eq!(
        observation_from_epoch(&e, UP, var, &bad_map),
        Err(OneStageError::InvalidConfig)
    );
    assert_eq!(
        observation_from_epoch(&e, [f32::NAN, 0.0, 1.0], var, &m),
        Err(OneStageError::NonFiniteInput)
    );
    assert_eq!(
        observation_from_epoch(&e, [0.0, 0.0, 1.1], var, &m),
        Err(OneStageError::InvalidObservation)
    );
    assert_eq!(
        observation_from_epoch(&e, UP, [1.0, 0.0, 1.0], &m),
        Err(OneStageError::InvalidObservation)
    );
    let mut hot = e;
    hot.cn0_dbhz = 95.0;
    assert_eq!(
        observation_from_epoch(&hot, UP, var, &m),
        Err(OneStageError::InvalidObservation)
    );
}

#[test]
fn the_noise_floor_averages_each_input_and_lends_the_reference_to_tapless_slaves() {
    let mut floor = NoiseFloor::new(4);
    assert_eq!(floor.variance(1), None);
    // (I² + Q²)/2: input 0 → 50, input 1 → 200; input 2 has no noise tap
    let e = epoch([(0, 0); 3], [(10, 0), (0, 20), (0, 0)]);
    for _ in 0..3 {
        floor.add(&e.correlations);
    }
    assert_eq!(floor.variance(4), None, "three taps are not four");
    assert_eq!(floor.variance(3), Some([50.0, 200.0, 50.0]));
    // after the first `time_constant` taps it forgets with gain 1/4
    let e2 = epoch([(0, 0); 3], [(0, 0), (0, 40), (0, 0)]);
    floor.add(&e2.correlations);
    let v = floor.variance(1).unwrap();
    assert_eq!(v[0], 50.0, "a zero tap is skipped");
    assert!((v[1] - (200.0 + (800.0 - 200.0) / 4.0)).abs() < 1e-3);
}

#[test]
fn the_adapter_passes_locked_channels_once_the_noise_is_known() {
    let config = AdapterConfig {
        noise_min_taps: 5,
        ..AdapterConfig::default()
    };
    let mut adapter = ObservationAdapter::new(config).unwrap();
    let e = epoch([(400, 0); 3], [(20, 20); 3]);
    let mut unlocked = e;
    unlocked.lock.phase = false;
    let mut pulling = e;
    pulling.state = ChannelState::PullIn;
    let mut weak = e;
    weak.cn0_dbhz = 20.0;
    for bad in [unlocked, pulling, weak, e] {
        assert_eq!(adapter.observe(&bad, UP).unwrap(), None);
    }
    assert_eq!(adapter.noise().variance(4), Some([400.0; 3]));
    let o = adapter.observe(&e, UP).unwrap().unwrap();
    assert_eq!(o.prompt.i, [20.0; 3]);
    // an error leaves the adapter unchanged
    let before = adapter;
    assert!(adapter.observe(&e, [1.0, 1.0, 1.0]).is_err());
    assert_eq!(adapter, before);
    adapter.reset_noise();
    assert_eq!(adapter.noise().variance(1), None);
    let mut partial = e;
    partial.correlations.complete = false;
    assert_eq!(adapter.observe(&partial, UP).unwrap(), None);
    assert_eq!(
        adapter.noise().variance(1),
        None,
        "partial periods are ignored"
    );
}

#[test]
fn the_epoch_clock_rounds_the_middle_sample_to_the_grid() {
    let clock = EpochClock::new(1_000_000, 2600).unwrap();
    let mut c = epoch([(0, 0); 3], [(0, 0); 3]).correlations;
    c.samples = 2601;
    // middle 1_000_000 + 1300.5 − 1300 → epoch 0 up to just below +1300
    c.first_sample = 1_000_000 - 1300 - 1301;
    assert_eq!(clock.epoch_of(&c), None);
    c.first_sample = 1_000_000 - 1300 - 1300; // middle at −1299.5 → epoch 0
    assert_eq!(clock.epoch_of(&c), Some(0));
    c.first_sample = 1_000_000 + 2600 * 5 - 1300; // middle at +0.5 → epoch 5
    assert_eq!(clock.epoch_of(&c), Some(5));
    c.first_sample = 1_000_000 + 2600 * 5; // middle at +1300.5 → epoch 6
    assert_eq!(clock.epoch_of(&c), Some(6));
    assert_eq!(clock.sample_of(6), 1_000_000 + 15_600);
    assert_eq!(EpochClock::new(0, 0), Err(OneStageError::InvalidConfig));
    c.first_sample = u64::MAX;
    assert!(
        clock.epoch_of(&c).is_some(),
        "no overflow at the end of time"
    );
}

#[test]
fn the_epoch_clock_equals_the_wide_division_at_every_epoch_length() {
    // 16-bit digits below 32 768 samples per epoch, the 64-bit division above: both equal
    // round((middle − origin)/n) done in u128 for any stamp, over days of samples and at
    // the end of time.
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut c = epoch([(0, 0); 3], [(0, 0); 3]).correlations;
    for n in [1u32, 2600, 4092, 32_767, 32_768, 65_536, 100_000] {
        let origin = next() % (1 << 40);
        let clock = EpochClock::new(origin, n).unwrap();
        for k in 0..20_000 {
            c.first_sample = match k % 3 {
                0 => origin.wrapping_add(next() % (1 << 45)),
                1 => next(),
                _ => u64::MAX - next() % (1 << 20),
            };
            c.samples = n + (next() % 3) as u32 - 1;
            let twice_mid = u128::from(c.first_sample) * 2 + u128::from(c.samples);
            let want = (twice_mid + u128::from(n))
                .checked_sub(u128::from(origin) * 2)
                .map(|s| s / (2 * u128::from(n)))
                .and_then(|q| u64::try_from(q).ok());
            assert_eq!(clock.epoch_of(&c), want, "n {n} stamp {}", c.first_sample);
        }
    }
}
