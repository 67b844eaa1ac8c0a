//! Host cost of the attitude receiver (criterion), on the example flight (8 satellites at
//! 45 dB-Hz, 0.5 m triangle, gyro at 100 Hz), once its fine filter is locked: one epoch (the
//! observations of 8 satellites pushed and the epoch closed), and one 100-epoch window (100
//! epochs, a window close with the ambiguity upkeep, the least squares and the rigid-body
//! step, ten gyro samples). The observations are generated outside the timed part. The
//! target's instruction counts come from the firmware (printed by `.ci/run`).

use std::cell::{Cell, RefCell};
use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use gnss_attitude::attitude::one_stage::SatelliteObservation;
use gnss_attitude::receiver::example::ExampleFlight;
use gnss_attitude::receiver::{AttitudeReceiver, AttitudeSource, MAX_SATELLITES};

type Epoch = heapless::Vec<SatelliteObservation<f32>, MAX_SATELLITES>;

fn locked() -> (ExampleFlight, AttitudeReceiver, u64) {
    let mut flight = ExampleFlight::new(11);
    let mut r =
        AttitudeReceiver::new(ExampleFlight::config(true)).unwrap_or_else(|e| panic!("{e}"));
    flight
        .fly(&mut r, 0, 1000)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(r.attitude().source, AttitudeSource::Fine);
    (flight, r, 1000)
}

fn bench(c: &mut Criterion) {
    let (flight, r, k) = locked();
    let (flight, r, k) = (RefCell::new(flight), RefCell::new(r), Cell::new(k));
    c.bench_function("receiver epoch, 8 sats (push + close, no window)", |b| {
        b.iter_batched(
            || {
                // skip the window-closing epochs and the gyro samples: a plain epoch
                let mut e = k.get();
                while (e + 1) % 100 == 0 || e % 10 == 0 || e % 100 == 0 {
                    let (mut f, mut rr) = (flight.borrow_mut(), r.borrow_mut());
                    f.fly(&mut rr, e, e + 1).unwrap_or_else(|e| panic!("{e}"));
                    e += 1;
                }
                let obs: Epoch = flight.borrow_mut().observations(e);
                k.set(e + 1);
                (e, obs)
            },
            |(epoch, obs)| {
                let mut rr = r.borrow_mut();
                for o in obs.iter() {
                    let _ = rr.push_observation(epoch, black_box(o));
                }
                rr.close_through(black_box(epoch));
            },
            BatchSize::PerIteration,
        );
    });
    let (flight, r, k) = locked();
    let (flight, r, k) = (RefCell::new(flight), RefCell::new(r), Cell::new(k));
    c.bench_function(
        "receiver window: 100 epochs of 8 sats + 10 gyro samples",
        |b| {
            b.iter_batched(
                || {
                    let mut f = flight.borrow_mut();
                    let e0 = k.get();
                    let epochs: Vec<(u64, Epoch)> =
                        (e0..e0 + 100).map(|e| (e, f.observations(e))).collect();
                    let gyro: Vec<[f32; 3]> = (0..10).map(|n| f.gyro_increment(n)).collect();
                    let aiding = f.aiding(e0);
                    k.set(e0 + 100);
                    (epochs, gyro, aiding)
                },
                |(epochs, gyro, aiding)| {
                    let mut rr = r.borrow_mut();
                    let _ = rr.set_aiding(&aiding);
                    let mut last = 0;
                    for (i, (epoch, obs)) in epochs.iter().enumerate() {
                        if i % 10 == 0 {
                            let _ = rr.push_gyro_increment(&gyro[i / 10]);
                        }
                        for o in obs.iter() {
                            let _ = rr.push_observation(*epoch, black_box(o));
                        }
                        last = *epoch;
                    }
                    rr.close_through(black_box(last));
                },
                BatchSize::PerIteration,
            );
        },
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
