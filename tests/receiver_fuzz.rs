//! The receiver under an adversary: a receiver in fine tracking gets a random sequence of
//! calls with poisoned arguments (NaN, ±∞, huge and subnormal values, epochs out of order,
//! jumps of an hour), then the valid signals of the example flight again. Every call returns
//! or refuses without panicking; a refused call leaves the attitude and the health as they
//! were; the attitude stays finite; and the valid signals bring a fine attitude back within
//! 20 s, close to the truth — never stuck, never confidently wrong.

mod common;

use gnss_attitude::attitude::one_stage::{PromptIq, SatelliteObservation};
use gnss_attitude::receiver::example::ExampleFlight;
use gnss_attitude::receiver::{AttitudeReceiver, AttitudeSource, SatelliteAiding};
use proptest::prelude::*;

/// One call of the public API.
#[derive(Clone, Debug)]
enum Call {
    Aiding {
        prn: u8,
        epoch_offset: i64,
        los: [f32; 3],
        los_rate: [f32; 3],
    },
    GyroIncrement([f32; 3]),
    GyroPulses([i32; 3]),
    Observation {
        epoch_offset: i64,
        prn: u8,
        los: [f32; 3],
        iq: [f32; 6],
        noise_var: f32,
        cn0_dbhz: f32,
    },
    Close(i64),
}

/// A float that is sometimes ordinary and often poisoned.
fn float() -> impl Strategy<Value = f32> {
    common::poisoned_float()
}

/// An epoch offset from the receiver's current epoch: mostly near, sometimes far back or an
/// hour ahead.
fn epoch_offset() -> impl Strategy<Value = i64> {
    prop_oneof![
        6 => -50i64..50,
        1 => -100_000i64..0,
        1 => Just(3_600_000i64),
        1 => Just(1i64 << 40), // 35 years of epochs
        1 => Just(i64::MAX),
    ]
}

fn call() -> impl Strategy<Value = Call> {
    prop_oneof![
        (
            0u8..40,
            epoch_offset(),
            [float(), float(), float()],
            [float(), float(), float()]
        )
            .prop_map(|(prn, epoch_offset, los, los_rate)| Call::Aiding {
                prn,
                epoch_offset,
                los,
                los_rate
            }),
        [float(), float(), float()].prop_map(Call::GyroIncrement),
        [any::<i32>(), any::<i32>(), any::<i32>()].prop_map(Call::GyroPulses),
        (
            epoch_offset(),
            0u8..40,
            [float(), float(), float()],
            [float(), float(), float(), float(), float(), float()],
            float(),
            prop_oneof![3 => 30.0f32..60.0, 1 => float()]
        )
            .prop_map(|(epoch_offset, prn, los, iq, noise_var, cn0_dbhz)| {
                Call::Observation {
                    epoch_offset,
                    prn,
                    los,
                    iq,
                    noise_var,
                    cn0_dbhz,
                }
            }),
        epoch_offset().prop_map(Call::Close),
    ]
}

/// Latest epoch the calls reach: far enough for any jump, with room for the flight after.
const LATEST_EPOCH: i64 = 1 << 50;

fn at(receiver: &AttitudeReceiver, offset: i64) -> u64 {
    let now = receiver.epoch().unwrap_or(0) as i64;
    now.saturating_add(offset).clamp(0, LATEST_EPOCH) as u64
}

/// Applies `call`; returns whether the receiver refused it.
fn apply(receiver: &mut AttitudeReceiver, call: &Call) -> bool {
    match *call {
        Call::Aiding {
            prn,
            epoch_offset,
            los,
            los_rate,
        } => {
            let epoch = at(receiver, epoch_offset);
            receiver
                .set_aiding(&[SatelliteAiding {
                    prn,
                    epoch,
                    los,
                    los_rate,
                }])
                .is_err()
        }
        Call::GyroIncrement(theta) => receiver.push_gyro_increment(&theta).is_err(),
        Call::GyroPulses(counts) => receiver.push_gyro_pulses(counts).is_err(),
        Call::Observation {
            epoch_offset,
            prn,
            los,
            iq,
            noise_var,
            cn0_dbhz,
        } => {
            let epoch = at(receiver, epoch_offset);
            let observation = SatelliteObservation {
                id: prn,
                los,
                prompt: PromptIq {
                    i: [iq[0], iq[1], iq[2]],
                    q: [iq[3], iq[4], iq[5]],
                },
                noise_var,
                cn0_dbhz,
            };
            receiver.push_observation(epoch, &observation).is_err()
        }
        Call::Close(offset) => {
            let epoch = at(receiver, offset);
            receiver.close_through(epoch);
            false
        }
    }
}

/// Angle between two attitudes, degrees.
fn angle_deg(
    a: &gnss_attitude::geometry::Quaternion<f32>,
    b: &gnss_attitude::geometry::Quaternion<f32>,
) -> f32 {
    let d = (a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z)
        .abs()
        .min(1.0);
    2.0 * d.acos().to_degrees()
}

/// The example flight's receiver after 1.5 s: in fine tracking.
fn tracking_receiver(flight: &mut ExampleFlight) -> AttitudeReceiver {
    let mut receiver = AttitudeReceiver::new(ExampleFlight::config(true)).unwrap();
    flight.fly(&mut receiver, 0, 1500).unwrap();
    assert_eq!(receiver.attitude().source, AttitudeSource::Fine);
    receiver
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 100, ..ProptestConfig::default() })]

    #[test]
    fn any_call_sequence_leaves_a_receiver_that_recovers(calls in prop::collection::vec(call(), 1..60)) {
        let mut flight = ExampleFlight::new(3);
        let mut receiver = tracking_receiver(&mut flight);
        for call in &calls {
            let (attitude, health) = (receiver.attitude(), receiver.health());
            let refused = apply(&mut receiver, call);
            if refused {
                prop_assert_eq!(receiver.attitude(), attitude, "{:?}", call);
                prop_assert_eq!(receiver.health(), health, "{:?}", call);
            }
            let q = receiver.attitude().q_rb;
            prop_assert!(
                [q.w, q.x, q.y, q.z].iter().all(|v| v.is_finite()),
                "{:?} after {:?}", q, call
            );
        }
        // the valid signals again, from the first aiding epoch (the flight aids every 100
        // epochs) after the latest epoch the receiver has seen
        let from = receiver.epoch().map_or(0, |e| (e + 1).div_ceil(100) * 100);
        let to = from + 20_000;
        flight.fly(&mut receiver, from, to).unwrap();
        let att = receiver.attitude();
        prop_assert_eq!(att.source, AttitudeSource::Fine, "after {:?}", calls);
        let error = angle_deg(&att.q_rb, &flight.attitude(to - 1));
        // within 0.2° and within 5σ of what the receiver reports
        let sigma = (att.covariance[(0, 0)] + att.covariance[(1, 1)] + att.covariance[(2, 2)])
            .sqrt()
            .to_degrees();
        prop_assert!(error < 0.2 && error < 5.0 * sigma.max(0.005), "error {}° σ {}°", error, sigma);
    }
}
