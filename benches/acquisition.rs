//! Host throughput of the acquisition (criterion): the case, 12 PRNs over ±10 kHz
//! (500 Hz bins, 41 bins) from 10 ms of 2.6 Msps complex samples (a synthesized CS8 recording
//! of 8 satellites at 40–50 dB-Hz, decoded by the core), with `Acquisition<2048>`:
//! * one engine, the 12 PRNs one after the other (one core);
//! * `host_sim::chain::search_prns`, what `host-sim acquire` runs (rayon over PRNs, one
//!   engine per worker);
//!
//! and one PRN over ±50 kHz (201 bins, the LEO search) from the same 10 ms.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use gnss_attitude::signal::Prn;
use gnss_attitude::tracking::{Acquisition, AcquisitionConfig};
use host_sim::chain::search_prns;
use host_sim::record::synthesize::scene;
use host_sim::record::{Dynamics, FileFormat, SynthSpec};
use host_sim::synth::quantize::{decode, encode};

fn bench(c: &mut Criterion) {
    let fs = 2.6e6;
    let spec = SynthSpec {
        format: FileFormat::parse("cs8").unwrap_or_else(|e| panic!("{e}")),
        sample_rate_hz: fs,
        intermediate_frequency_hz: None,
        seconds: 0.011,
        antennas: 1,
        dynamics: Dynamics::Static,
        satellites: 8,
        cn0_min_dbhz: 40.0,
        cn0_max_dbhz: 50.0,
        seed: 1,
        ..SynthSpec::default()
    };
    let (sc, truth) = scene(&spec).unwrap_or_else(|e| panic!("{e}"));
    let config = |max: f32| AcquisitionConfig {
        sample_rate_hz: fs,
        intermediate_frequency_hz: 0.0,
        doppler_max_hz: max,
        doppler_step_hz: 500.0,
        noncoherent_ms: 10,
        false_alarm_probability: 1e-5,
    };
    let ground = config(10_000.0);
    let n = ground.samples_needed();
    let streams =
        encode(spec.format.sample, &sc.synthesize(0, n)).unwrap_or_else(|e| panic!("{e}"));
    let planar = decode(spec.format.sample, &streams, 1, n).unwrap_or_else(|e| panic!("{e}"));
    let (i, q) = (&planar.i[0][..], &planar.q[0][..]);
    // The 8 synthesized PRNs and 4 absent ones.
    let mut prns: Vec<u8> = truth.iter().map(|s| s.prn).collect();
    prns.extend(
        (1..=32)
            .filter(|p| !prns.contains(p))
            .take(4)
            .collect::<Vec<_>>(),
    );
    let mut engine = Box::new(Acquisition::<2048>::new().unwrap_or_else(|e| panic!("{e}")));
    let mut group = c.benchmark_group("acquisition");
    group.sample_size(10);
    group.bench_function(
        "12 PRNs x 41 bins (+-10 kHz) x 10 ms @ 2.6 Msps, one core",
        |b| {
            b.iter(|| {
                for &p in &prns {
                    let prn = Prn::new(p).unwrap_or_else(|| panic!("PRN {p}"));
                    black_box(
                        engine
                            .search(prn, black_box(i), Some(black_box(q)), 0, &ground)
                            .unwrap_or_else(|e| panic!("{e}")),
                    );
                }
            })
        },
    );
    group.bench_function(
        "12 PRNs x 41 bins (+-10 kHz) x 10 ms @ 2.6 Msps, rayon (host-sim acquire)",
        |b| {
            b.iter(|| {
                black_box(
                    search_prns(black_box(i), Some(q), 0, &prns, &ground)
                        .unwrap_or_else(|e| panic!("{e}")),
                )
            })
        },
    );
    let leo = config(50_000.0);
    let prn = Prn::new(prns[0]).unwrap_or_else(|| panic!("PRN"));
    group.bench_function(
        "1 PRN x 201 bins (+-50 kHz) x 10 ms @ 2.6 Msps, one core",
        |b| {
            b.iter(|| {
                black_box(
                    engine
                        .search(prn, black_box(i), Some(black_box(q)), 0, &leo)
                        .unwrap_or_else(|e| panic!("{e}")),
                )
            })
        },
    );
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
