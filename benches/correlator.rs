//! Host throughput of the fixed-point correlator (criterion): one satellite, three antennas,
//! E/P/L + noise taps, one 1 ms code period per iteration, at 2.6 and 4.092 Msps, complex
//! (CS8-decoded) and real 2-bit samples. Throughput is printed in Msamples·channel/s, a
//! channel being one antenna × one satellite (three per iteration).
//!
//! Reference, measured on this kind of machine in one session (Pocket SDR, `sdr_func.c`, mix +
//! 4 correlators, one 1 ms epoch at 2.6 Msps, one channel): AVX2 build 2.57 µs, i.e.
//! 1012 Msamples·channel/s; scalar build (no SIMD) 12.2 µs (213 Msamples·channel/s). The
//! figures here are the default x86-64 build (SSE2 only: no `-C target-cpu`), per iteration of
//! three channels (per channel-epoch = time / 3).
//!
//! The bit-parallel correlator (`signal::bitwise`) runs the same case (3 antennas × 1
//! satellite, one code period at 2.6 Msps, complex) on 1- and 2-bit planes, with prompt-only
//! slaves (the design: 2 taps per channel on average) and with E/P/L+N on every antenna (the
//! same four taps per channel as the `i8` and Pocket SDR figures); the packing of 1 ms of
//! `sm2iq` bytes of three antennas is measured too.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use gnss_attitude::signal::bitwise::{
    BitBlock, BitCorrelator, BitCorrelatorConfig, BitScratch, CarrierLevels, CodeTable,
    PlaneBuffer, PlaneFormat, Resolution,
};
use gnss_attitude::signal::{
    Correlator, CorrelatorConfig, Prn, SampleBlock, SampleFormat, SlaveTaps,
};

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

/// Bit planes of one antenna: pseudo-random 2-bit complex samples (sm2iq bytes), packed.
fn planes_for(seed: u32, n: usize, format: PlaneFormat) -> PlaneBuffer<128> {
    let mut x = seed.wrapping_mul(2_654_435_761) | 1;
    let bytes: Vec<u8> = (0..n.div_ceil(2))
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x >> 24) as u8
        })
        .collect();
    let mut buf = PlaneBuffer::<128>::new(format);
    buf.pack_bytes(SampleFormat::SignMagnitude2 { complex: true }, &bytes, 0)
        .unwrap_or_else(|e| panic!("{e}"));
    buf
}

/// The bit-parallel correlator on the same case: 3 antennas x 1 satellite, one 1 ms code
/// period at 2.6 Msps, complex; 1- and 2-bit samples, 2- and 3-level carriers, prompt-only
/// slaves (the design) and E/P/L+N on every antenna (per channel the same work as the i8 and
/// Pocket SDR figures). Plus the packing of 1 ms of sm2iq bytes of 3 antennas.
fn bench_bitwise(c: &mut Criterion) {
    let mut group = c.benchmark_group("bit-parallel correlator");
    let fs = 2.6e6;
    let n = 2608;
    let table = CodeTable::new(fs).unwrap_or_else(|e| panic!("{e}"));
    for &(res, levels, slaves) in &[
        (Resolution::OneBit, CarrierLevels::Two, SlaveTaps::Prompt),
        (Resolution::OneBit, CarrierLevels::Two, SlaveTaps::All),
        (Resolution::TwoBit, CarrierLevels::Two, SlaveTaps::Prompt),
        (Resolution::TwoBit, CarrierLevels::Two, SlaveTaps::All),
        (Resolution::OneBit, CarrierLevels::Three, SlaveTaps::Prompt),
        (Resolution::TwoBit, CarrierLevels::Three, SlaveTaps::Prompt),
    ] {
        let format = PlaneFormat {
            resolution: res,
            complex: true,
        };
        let bufs: Vec<PlaneBuffer<128>> = (0..3).map(|a| planes_for(a + 1, n, format)).collect();
        let block = BitBlock::new(
            0,
            &table,
            [bufs[0].planes(), bufs[1].planes(), bufs[2].planes()],
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let config = BitCorrelatorConfig {
            correlator: CorrelatorConfig {
                sample_rate_hz: fs,
                intermediate_frequency_hz: 0.0,
                early_late_offset_chips: 0.5,
                slave_taps: slaves,
            },
            format,
            carrier: levels,
        };
        let prn = Prn::new(5).unwrap_or_else(|| panic!());
        let mut corr = BitCorrelator::<3>::new(prn, &config).unwrap_or_else(|e| panic!("{e}"));
        corr.set_carrier_frequency(2345.0)
            .unwrap_or_else(|e| panic!("{e}"));
        let per_epoch = corr.code().samples_to_wrap();
        group.throughput(Throughput::Elements(3 * per_epoch));
        let name = format!(
            "3 antennas x 1 sat, {}, 2.600 Msps complex {}, {}-level carrier",
            match slaves {
                SlaveTaps::Prompt => "E/P/L+N ref + P slaves",
                _ => "E/P/L+N all",
            },
            match res {
                Resolution::OneBit => "1-bit",
                Resolution::TwoBit => "2-bit",
            },
            match levels {
                CarrierLevels::Two => 2,
                CarrierLevels::Three => 3,
            }
        );
        // (one scratch for the run, as a receiver's channels share one)
        let mut scratch = BitScratch::new();
        group.bench_function(name, |b| {
            b.iter(|| {
                corr.set_code_phase(0.0).unwrap_or_else(|e| panic!("{e}"));
                let mut cursor = 0;
                black_box(
                    corr.run_in(black_box(&block), &mut cursor, &mut scratch)
                        .unwrap_or_else(|e| panic!("{e}")),
                )
            })
        });
    }
    let format = PlaneFormat {
        resolution: Resolution::TwoBit,
        complex: true,
    };
    let bytes: Vec<Vec<u8>> = (0..3u32)
        .map(|a| {
            (0..1300u32)
                .map(|k| (k.wrapping_mul(2_654_435_761) >> (a + 7)) as u8)
                .collect()
        })
        .collect();
    let mut bufs: Vec<PlaneBuffer<128>> = (0..3).map(|_| PlaneBuffer::new(format)).collect();
    group.throughput(Throughput::Elements(3 * 2600));
    group.bench_function(
        "packing 1 ms of sm2iq bytes, 3 antennas, 2-bit planes",
        |b| {
            b.iter(|| {
                for (buf, by) in bufs.iter_mut().zip(&bytes) {
                    black_box(
                        buf.pack_bytes(
                            SampleFormat::SignMagnitude2 { complex: true },
                            black_box(by),
                            0,
                        )
                        .unwrap_or_else(|e| panic!("{e}")),
                    );
                }
            })
        },
    );
    group.finish();
}

criterion_group!(benches, bench, bench_bitwise);
criterion_main!(benches);
