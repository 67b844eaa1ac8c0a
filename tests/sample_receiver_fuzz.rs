//! The receiver from raw samples under an adversary (issue 15): a [`SampleReceiver`] gets a
//! random sequence of calls — sample blocks of random length (empty ones too) that continue
//! the stream, leave a gap, go back or start near `u64::MAX`; searches on too few or enough
//! samples; channel starts from detections with poisoned values and stops for random PRNs;
//! aiding and gyro samples with poisoned floats; and front-end configurations with poisoned
//! fields. Every call returns or refuses without panicking; a refused call leaves the
//! observable state (attitude, health, epoch, channels) as it was; no output is non-finite;
//! and afterwards valid observations bring the receiver to a fine attitude.

mod common;

use gnss_attitude::receiver::example::ExampleFlight;
use gnss_attitude::receiver::{
    AttitudeSource, ChannelStatus, ReceiverAttitude, ReceiverHealth, SampleFrontConfig,
    SampleReceiver, SatelliteAiding,
};
use gnss_attitude::signal::{Prn, SampleBlock};
use gnss_attitude::tracking::SearchResult;
use proptest::prelude::*;

/// Two channels, 1024-point acquisition: the smallest receiver, so that the cases are cheap.
type Front = SampleReceiver<2, 1024>;

/// The sample rate of the cases, Hz (one sample per chip).
const FS: f64 = 1.023e6;

fn front_config() -> SampleFrontConfig {
    let mut config = SampleFrontConfig::leo_complex(FS);
    config.acquisition.doppler_max_hz = 1000.0;
    config.acquisition.noncoherent_ms = 2;
    config
}

/// A float that is sometimes ordinary and often poisoned.
fn float() -> impl Strategy<Value = f32> {
    common::poisoned_float()
}

/// Where a block starts relative to the stream's next sample.
#[derive(Clone, Copy, Debug)]
enum Start {
    Continue,
    Gap(u64),
    Back(u64),
    NearMax(u64),
}

fn start() -> impl Strategy<Value = Start> {
    prop_oneof![
        6 => Just(Start::Continue),
        1 => (1u64..5_000_000).prop_map(Start::Gap),
        1 => (1u64..100_000).prop_map(Start::Back),
        1 => (0u64..3000).prop_map(Start::NearMax),
    ]
}

/// One call of the public API.
#[derive(Clone, Debug)]
enum Call {
    Push {
        start: Start,
        len: usize,
        seed: u8,
    },
    Search {
        prn: u8,
        len: usize,
    },
    Start {
        prn: u8,
        doppler: f32,
        code: f32,
        first: Start,
    },
    Release(u8),
    Aiding {
        prn: u8,
        los: [f32; 3],
    },
    Gyro([f32; 3]),
}

fn call() -> impl Strategy<Value = Call> {
    prop_oneof![
        5 => (start(), prop_oneof![1 => Just(0usize), 4 => 1usize..2600, 1 => 2600usize..6000], any::<u8>())
            .prop_map(|(start, len, seed)| Call::Push { start, len, seed }),
        1 => (0u8..40, prop_oneof![Just(100usize), Just(4100usize)])
            .prop_map(|(prn, len)| Call::Search { prn, len }),
        2 => (0u8..40, prop_oneof![3 => -5000.0f32..5000.0, 1 => float()], prop_oneof![3 => 0.0f32..1023.0, 1 => float()], start())
            .prop_map(|(prn, doppler, code, first)| Call::Start { prn, doppler, code, first }),
        1 => (0u8..40).prop_map(Call::Release),
        1 => (0u8..40, [float(), float(), float()]).prop_map(|(prn, los)| Call::Aiding { prn, los }),
        1 => [float(), float(), float()].prop_map(Call::Gyro),
    ]
}

/// What the caller can see of the receiver.
#[derive(Clone, Debug, PartialEq)]
struct Observable {
    attitude: ReceiverAttitude,
    health: ReceiverHealth,
    epoch: Option<u64>,
    channels: Vec<ChannelStatus>,
}

fn observe(rx: &Front) -> Observable {
    Observable {
        attitude: rx.attitude(),
        health: rx.receiver().health(),
        epoch: rx.receiver().epoch(),
        channels: rx.channels().copied().collect(),
    }
}

fn finite(att: &ReceiverAttitude) -> bool {
    let q = att.q_rb;
    [q.w, q.x, q.y, q.z].iter().all(|v| v.is_finite())
        && att.covariance.iter().all(|v| v.is_finite())
        && att.euler.yaw.is_finite()
        && att.euler.pitch.is_finite()
        && att.euler.roll.is_finite()
}

/// Noise-like samples (a cheap hash of the index), never all zero.
fn samples(len: usize, seed: u8) -> Vec<i8> {
    (0..len)
        .map(|n| {
            let h = (n as u32 ^ u32::from(seed)).wrapping_mul(0x9E37_79B1);
            ((h >> 24) as i8) / 8
        })
        .collect()
}

fn first_sample(next: u64, start: Start) -> u64 {
    match start {
        Start::Continue => next,
        Start::Gap(n) => next.saturating_add(n),
        Start::Back(n) => next.saturating_sub(n),
        Start::NearMax(n) => u64::MAX - n,
    }
}

/// Applies `call`; returns whether the receiver refused it.
fn apply(rx: &mut Front, next: &mut u64, call: &Call) -> bool {
    match *call {
        Call::Push { start, len, seed } => {
            let (i, q) = (samples(len, seed), samples(len, seed.wrapping_add(1)));
            let first = first_sample(*next, start);
            let Ok(block) = SampleBlock::complex(first, [&i; 3], [&q; 3]) else {
                return true;
            };
            let refused = rx.push_samples(&block).is_err();
            if !refused {
                *next = first.saturating_add(len as u64);
            }
            refused
        }
        Call::Search { prn, len } => {
            let Some(prn) = Prn::new(prn) else {
                return true;
            };
            let (i, q) = (samples(len, 3), samples(len, 4));
            rx.search(prn, &i, Some(&q), *next).is_err()
        }
        Call::Start {
            prn,
            doppler,
            code,
            first,
        } => {
            let Some(prn) = Prn::new(prn) else {
                return true;
            };
            let result = SearchResult {
                prn,
                detected: true,
                metric: 10.0,
                threshold: 1.0,
                doppler_hz: doppler,
                code_phase_chips: code,
                first_sample: first_sample(*next, first),
            };
            rx.start(&result).is_err()
        }
        Call::Release(prn) => {
            if let Some(prn) = Prn::new(prn) {
                rx.release(prn);
            }
            false
        }
        Call::Aiding { prn, los } => {
            let epoch = rx.receiver().epoch().unwrap_or(0);
            let aiding = SatelliteAiding {
                prn,
                epoch,
                los,
                los_rate: [0.0; 3],
            };
            rx.receiver_mut().set_aiding(&[aiding]).is_err()
        }
        Call::Gyro(theta) => rx.receiver_mut().push_gyro_increment(&theta).is_err(),
    }
}

/// A front-end configuration with one poisoned field.
fn poisoned_front() -> impl Strategy<Value = SampleFrontConfig> {
    (0usize..7, float(), any::<u64>()).prop_map(|(field, v, n)| {
        let mut c = front_config();
        match field {
            0 => c.acquisition.sample_rate_hz = f64::from(v),
            1 => c.acquisition.doppler_max_hz = v,
            2 => c.acquisition.doppler_step_hz = v,
            3 => c.acquisition.false_alarm_probability = v,
            4 => c.samples_per_epoch = (n % 4) as u32,
            5 => c.epoch_origin_sample = n,
            _ => c.release_after_samples = n,
        }
        c
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 100, ..ProptestConfig::default() })]

    #[test]
    fn any_call_sequence_on_the_sample_receiver_refuses_cleanly_and_recovers(
        gyro in any::<bool>(),
        calls in prop::collection::vec(call(), 1..40),
    ) {
        let mut rx = Front::new(ExampleFlight::config(gyro), front_config()).unwrap();
        let mut next = 0u64;
        for call in &calls {
            let before = observe(&rx);
            let refused = apply(&mut rx, &mut next, call);
            let after = observe(&rx);
            if refused {
                prop_assert_eq!(&after, &before, "{:?}", call);
            }
            prop_assert!(finite(&after.attitude), "{:?} after {:?}", after.attitude, call);
            prop_assert!(after.channels.iter().all(|c| c.cn0_dbhz.is_finite()), "{:?}", after.channels);
        }
        // the stream goes on: a block continuing it is accepted
        let (i, q) = (samples(2600, 9), samples(2600, 10));
        let block = SampleBlock::complex(next, [&i; 3], [&q; 3]).unwrap();
        prop_assert!(rx.push_samples(&block).is_ok(), "after {:?}", calls);
        // valid observations from the first aiding epoch (the flight aids every 100 epochs)
        // after the latest epoch the receiver has seen
        let from = rx.receiver().epoch().map_or(0, |e| (e + 1).div_ceil(100) * 100);
        prop_assume!(from < 1 << 50);
        let mut flight = ExampleFlight::new(7);
        flight.fly(rx.receiver_mut(), from, from + 1500).unwrap();
        let att = rx.attitude();
        prop_assert!(finite(&att));
        prop_assert_eq!(att.source, AttitudeSource::Fine, "after {:?}", calls);
        prop_assert!(att.q_rb.angle_to(&flight.attitude(att.epoch)).to_degrees() < 0.5);
    }

    #[test]
    fn a_poisoned_front_end_configuration_is_refused_or_runs_finite(config in poisoned_front()) {
        let Ok(mut rx) = Front::new(ExampleFlight::config(true), config) else {
            return Ok(());
        };
        let (i, q) = (samples(3000, 1), samples(3000, 2));
        let block = SampleBlock::complex(0, [&i; 3], [&q; 3]).unwrap();
        let _ = rx.search(Prn::new(5).unwrap(), &i, Some(&q), 0);
        let _ = rx.push_samples(&block);
        prop_assert!(finite(&rx.attitude()));
    }
}
