//! Host throughput of the fixed-point correlator (criterion): one satellite, three antennas,
//! E/P/L + noise taps, one 1 ms code period per iteration, at 2.6 and 4.092 Msps, complex
//! (CS8-decoded) and real 2-bit samples. Throughput is printed in Msamples·channel/s, a
//! channel being one antenna × one satellite (three per iteration).
//!
//! Reference (Pocket SDR, `sdr_func.c`, AVX2 build, mix + 4 correlators, one 1 ms epoch at
//! 2.6 Msps, one channel): 4.4 µs, i.e. 591 Msamples·channel/s; scalar build 23.3 µs
//! (112 Msamples·channel/s).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use gnss_attitude::signal::{Correlator, CorrelatorConfig, Prn, SampleBlock};

fn samples(n: usize, seed: u32, two_bit: bool) -> Vec<i8> {
    let mut x = seed.wrapping_mul(2_654_435_761) | 1;
    (0..n)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            if two_bit {
                [1i8, 3, -1, -3][(x >> 30) as usize]
            } else {
                (x >> 24) as i8 / 4
            }
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("correlator");
    for &(fs, complex) in &[
        (2.6e6, true),
        (4.092e6, true),
        (2.6e6, false),
        (4.092e6, false),
    ] {
        let n = (fs / 1000.0) as usize + 8;
        let cfg = CorrelatorConfig {
            sample_rate_hz: fs,
            intermediate_frequency_hz: if complex { 0.0 } else { fs / 4.0 },
            early_late_offset_chips: 0.5,
            slave_taps: gnss_attitude::signal::SlaveTaps::All,
        };
        let ant: Vec<(Vec<i8>, Vec<i8>)> = (0..3)
            .map(|a| {
                (
                    samples(n, 2 * a + 1, !complex),
                    samples(n, 2 * a + 2, !complex),
                )
            })
            .collect();
        let block = if complex {
            SampleBlock::complex(
                0,
                [&ant[0].0[..], &ant[1].0[..], &ant[2].0[..]],
                [&ant[0].1[..], &ant[1].1[..], &ant[2].1[..]],
            )
        } else {
            SampleBlock::real(0, [&ant[0].0[..], &ant[1].0[..], &ant[2].0[..]])
        }
        .unwrap_or_else(|e| panic!("{e}"));
        let mut corr = Correlator::<3>::new(Prn::new(5).unwrap_or_else(|| panic!()), &cfg)
            .unwrap_or_else(|e| panic!("{e}"));
        corr.set_carrier_frequency(cfg.intermediate_frequency_hz + 2345.0)
            .unwrap_or_else(|e| panic!("{e}"));
        let per_epoch = corr.code().samples_to_wrap();
        group.throughput(Throughput::Elements(3 * per_epoch));
        let name = format!(
            "3 antennas x 1 sat, E/P/L+N, {:.3} Msps {}",
            fs / 1e6,
            if complex {
                "complex i8"
            } else {
                "real 2-bit IF"
            }
        );
        group.bench_function(name, |b| {
            b.iter(|| {
                corr.set_code_phase(0.0).unwrap_or_else(|e| panic!("{e}"));
                let mut cursor = 0;
                black_box(
                    corr.run(black_box(&block), &mut cursor)
                        .unwrap_or_else(|e| panic!("{e}")),
                )
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
