//! The fixed-point signal chain against the standard and against f64 references: C/A codes
//! (IS-GPS-200), sample formats, the correlator (f64 reference correlator on the same samples,
//! overflow at the largest epoch), acquisition and tracking on synthesized three-antenna
//! samples.

use gnss_attitude::signal::ca_code::{
    cyclic_correlation, generate_code_bits, Prn, CA_CODE_LENGTH, G2_TAPS, QUIET_OFFSET_CHIPS,
};
use gnss_attitude::signal::correlator::{MAX_SAMPLES_PER_EPOCH, MAX_SAMPLE_RATE_HZ};
use gnss_attitude::signal::nco::{CARRIER_REPLICA_MAX_ERROR, COS_TABLE, SIN_TABLE};
use gnss_attitude::signal::{
    Correlator, CorrelatorConfig, EpochCorrelations, SampleBlock, SampleFormat,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// IS-GPS-200 Table 3-Ia, "First 10 Chips C/A" (octal), PRN 1–32.
const FIRST_TEN_CHIPS_OCTAL: [u16; 32] = [
    0o1440, 0o1620, 0o1710, 0o1744, 0o1133, 0o1455, 0o1131, 0o1454, 0o1626, 0o1504, 0o1642, 0o1750,
    0o1764, 0o1772, 0o1775, 0o1776, 0o1156, 0o1467, 0o1633, 0o1715, 0o1746, 0o1763, 0o1063, 0o1706,
    0o1743, 0o1761, 0o1770, 0o1774, 0o1127, 0o1453, 0o1625, 0o1712,
];

/// IS-GPS-200 Table 3-Ia, "Code Delay Chips" (the G2 delay of each PRN).
const G2_DELAY: [usize; 32] = [
    5, 6, 7, 8, 17, 18, 139, 140, 141, 251, 252, 254, 255, 256, 257, 258, 469, 470, 471, 472, 473,
    474, 509, 512, 513, 514, 515, 516, 859, 860, 861, 862,
];

fn prn(n: u8) -> Prn {
    Prn::new(n).unwrap()
}

#[test]
fn all_32_prns_match_is_gps_200_first_ten_chips() {
    for n in 1..=32u8 {
        assert_eq!(
            prn(n).first_ten_chips_octal(),
            FIRST_TEN_CHIPS_OCTAL[n as usize - 1],
            "PRN {n}"
        );
    }
}

/// An independent construction: G1 ⊕ (G2 delayed by the PRN's code delay), with plain
/// arrays and the register polynomials written out again.
#[test]
fn codes_equal_the_g2_delay_construction() {
    let mut g1 = [0u8; 1023];
    let mut g2 = [0u8; 1023];
    let (mut r1, mut r2) = ([1u8; 10], [1u8; 10]);
    for k in 0..1023 {
        g1[k] = r1[9];
        g2[k] = r2[9];
        let f1 = r1[2] ^ r1[9];
        let f2 = r2[1] ^ r2[2] ^ r2[5] ^ r2[7] ^ r2[8] ^ r2[9];
        r1.rotate_right(1);
        r2.rotate_right(1);
        r1[0] = f1;
        r2[0] = f2;
    }
    for n in 1..=32u8 {
        let delay = G2_DELAY[n as usize - 1];
        for k in 0..CA_CODE_LENGTH {
            let expected = g1[k] ^ g2[(k + 1023 - delay) % 1023];
            assert_eq!(prn(n).chip_bit(k), expected, "PRN {n} chip {k}");
        }
    }
    // The taps table is IS-GPS-200's (spot checks of its first and last rows).
    assert_eq!(G2_TAPS[0], (2, 6));
    assert_eq!(G2_TAPS[31], (4, 9));
    assert_eq!(generate_code_bits(0), [0; 32]);
}

#[test]
fn codes_are_balanced_and_gold() {
    for n in 1..=32u8 {
        let ones = (0..CA_CODE_LENGTH)
            .filter(|&k| prn(n).chip_bit(k) == 1)
            .count();
        assert_eq!(ones, 512, "PRN {n}");
    }
    // Auto- and cross-correlation take only the Gold values {−65, −1, 63} off the peak.
    let mut seen = std::collections::BTreeSet::new();
    for a in 1..=32u8 {
        for b in a..=32u8 {
            // All shifts for a few pairs, a stride of shifts for the rest (keeps the test fast).
            let stride = if b - a < 2 { 1 } else { 7 };
            for shift in (0..CA_CODE_LENGTH).step_by(stride) {
                if a == b && shift == 0 {
                    assert_eq!(cyclic_correlation(prn(a), prn(b), 0), 1023);
                    continue;
                }
                let r = cyclic_correlation(prn(a), prn(b), shift);
                assert!([-65, -1, 63].contains(&r), "PRN {a}×{b} shift {shift}: {r}");
                seen.insert(r);
            }
        }
    }
    assert_eq!(seen.into_iter().collect::<Vec<_>>(), vec![-65, -1, 63]);
}

#[test]
fn quiet_offsets_are_quiet() {
    for n in 1..=32u8 {
        let q = usize::from(QUIET_OFFSET_CHIPS[n as usize - 1]);
        assert!((6..70).contains(&q));
        assert_eq!(cyclic_correlation(prn(n), prn(n), q), -1);
        assert_eq!(cyclic_correlation(prn(n), prn(n), q + 1), -1);
    }
}

// ---------------------------------------------------------------------------------------------
// Sample formats

#[test]
fn sample_formats_decode_their_documented_layouts() {
    let mut i = [0i8; 16];
    let mut q = [0i8; 16];
    // CS8
    let n = SampleFormat::Cs8
        .decode(&[1, 0xff, 0x80, 0x7f], 0, &mut i, &mut q)
        .unwrap();
    assert_eq!(
        (n, &i[..2], &q[..2]),
        (2, &[1i8, -128][..], &[-1i8, 127][..])
    );
    // CS16 with rounding and saturation
    let words: Vec<u8> = [300i16, -300, 20000, -20000]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let n = SampleFormat::Cs16 { shift: 4 }
        .decode(&words, 0, &mut i, &mut q)
        .unwrap();
    assert_eq!(
        (n, &i[..2], &q[..2]),
        (2, &[19i8, 127][..], &[-19i8, -128][..])
    );
    // 2-bit sign/magnitude real: fields 00 01 10 11 → +1 +3 −1 −3
    let n = SampleFormat::SignMagnitude2 { complex: false }
        .decode(&[0b00_01_10_11], 0, &mut i, &mut [])
        .unwrap();
    assert_eq!((n, &i[..4]), (4, &[1i8, 3, -1, -3][..]));
    // 2-bit complex: I Q I Q
    let n = SampleFormat::SignMagnitude2 { complex: true }
        .decode(&[0b11_00_01_10], 0, &mut i, &mut q)
        .unwrap();
    assert_eq!((n, &i[..2], &q[..2]), (2, &[-3i8, 3][..], &[1i8, -1][..]));
    // 1-bit, MSB first, 1 → −1
    let n = SampleFormat::Sign1
        .decode(&[0b1000_0001], 0, &mut i, &mut [])
        .unwrap();
    assert_eq!((n, &i[..8]), (8, &[-1i8, 1, 1, 1, 1, 1, 1, -1][..]));
    // 1-bit complex: I0 Q0 I1 Q1 I2 Q2 I3 Q3, MSB first, 1 → −1
    let n = SampleFormat::Sign1Iq
        .decode(&[0b10_01_00_11], 0, &mut i, &mut q)
        .unwrap();
    assert_eq!(
        (n, &i[..4], &q[..4]),
        (4, &[-1i8, 1, 1, -1][..], &[1i8, -1, 1, -1][..])
    );
    // Four channels in a byte: channel c in bits 2c+1..2c
    let byte = 0b11_10_01_00u8;
    for (c, v) in [1i8, 3, -1, -3].iter().enumerate() {
        let n = SampleFormat::MultiChannel2 { channels: 4 }
            .decode(&[byte], c, &mut i, &mut [])
            .unwrap();
        assert_eq!((n, i[0]), (1, *v));
    }
    // Bad input: clear errors, no panic.
    assert!(SampleFormat::Cs8
        .decode(&[1, 2, 3], 0, &mut i, &mut q)
        .is_err());
    assert!(SampleFormat::Cs16 { shift: 9 }
        .decode(&[0; 4], 0, &mut i, &mut q)
        .is_err());
    assert!(SampleFormat::MultiChannel2 { channels: 3 }
        .decode(&[0], 3, &mut i, &mut [])
        .is_err());
    assert!(SampleFormat::Int8.decode(&[0], 1, &mut i, &mut []).is_err());
}

// ---------------------------------------------------------------------------------------------
// Correlator against an f64 reference

#[test]
fn carrier_table_bounds_hold() {
    for k in 0..256 {
        let (c, s) = (COS_TABLE[k], SIN_TABLE[k]);
        assert!(c.abs() <= 127 && s.abs() <= 127);
        assert!(c.abs() + s.abs() <= 180, "entry {k}: {c} {s}");
        let phi = 2.0 * std::f64::consts::PI * (k as f64 + 0.5) / 256.0;
        assert!((f64::from(c) - 127.0 * phi.cos()).abs() <= 0.5);
        assert!((f64::from(s) - 127.0 * phi.sin()).abs() <= 0.5);
    }
}

/// The exact correlation of one epoch, in f64, with the carrier phase and the code phase
/// taken from the same fixed-point NCO words (so that only the carrier table differs).
struct Reference {
    early: (f64, f64),
    prompt: (f64, f64),
    late: (f64, f64),
    noise: (f64, f64),
    sum_abs: f64,
}

#[allow(clippy::too_many_arguments)]
fn reference_epoch(
    xi: &[i8],
    xq: Option<&[i8]>,
    start: usize,
    n: usize,
    carrier_phase: u32,
    carrier_step: u32,
    code_phase: u64,
    code_step: u64,
    prn: Prn,
    offset: usize,
    noise_delay_chips: f64,
) -> Reference {
    let two32 = 4_294_967_296.0f64;
    let chip_at = |phase_units: f64| -> f64 {
        let chips = (phase_units / two32).rem_euclid(1023.0);
        f64::from(prn.chip(chips.floor() as usize))
    };
    let mut r = Reference {
        early: (0.0, 0.0),
        prompt: (0.0, 0.0),
        late: (0.0, 0.0),
        noise: (0.0, 0.0),
        sum_abs: 0.0,
    };
    for k in 0..n {
        let x = (
            f64::from(xi[start + k]),
            xq.map_or(0.0, |q| f64::from(q[start + k])),
        );
        let phase = (u64::from(carrier_phase) + k as u64 * u64::from(carrier_step)) as u32;
        let phi = 2.0 * std::f64::consts::PI * f64::from(phase) / two32;
        let (c, s) = (phi.cos(), phi.sin());
        // x · e^{−jφ}
        let m = (x.0 * c + x.1 * s, x.1 * c - x.0 * s);
        let p = code_phase as f64 + k as f64 * code_step as f64;
        let d = offset as f64 * code_step as f64;
        let taps = [
            (&mut r.early, chip_at(p + d)),
            (&mut r.prompt, chip_at(p)),
            (&mut r.late, chip_at(p - d)),
            (&mut r.noise, chip_at(p - noise_delay_chips * two32)),
        ];
        for (acc, code) in taps {
            acc.0 += m.0 * code;
            acc.1 += m.1 * code;
        }
        r.sum_abs += (x.0 * x.0 + x.1 * x.1).sqrt();
    }
    r
}

/// Synthesizes a noisy GPS-like signal (PRN 7, Doppler, code phase) in f64 and quantizes it
/// into `format`, returning planar samples as the format decodes them.
fn synth_samples(
    format: SampleFormat,
    fs: f64,
    fif: f64,
    n: usize,
    seed: u64,
) -> (Vec<i8>, Vec<i8>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let bytes_len = format.bytes_for(n).unwrap();
    let mut bytes = vec![0u8; bytes_len];
    rng.fill(&mut bytes[..]);
    // Random bytes give every code point of every format; add a signal by biasing the
    // 8-bit formats towards a carrier-modulated code (a strong signal exercises the sums).
    if matches!(format, SampleFormat::Cs8 | SampleFormat::Int8) {
        for k in 0..n {
            let t = k as f64 / fs;
            let chip = prn(7).chip(((t * 1.023e6 + 100.3) % 1023.0) as usize);
            let phi = 2.0 * std::f64::consts::PI * (fif + 1234.5) * t;
            let v = 40.0 * f64::from(chip);
            match format {
                SampleFormat::Cs8 => {
                    bytes[2 * k] =
                        ((bytes[2 * k] as i8 as f64 / 4.0) + v * phi.cos()).round() as i8 as u8;
                    bytes[2 * k + 1] =
                        ((bytes[2 * k + 1] as i8 as f64 / 4.0) + v * phi.sin()).round() as i8 as u8;
                }
                _ => bytes[k] = ((bytes[k] as i8 as f64 / 4.0) + v * phi.cos()).round() as i8 as u8,
            }
        }
    }
    let mut i = vec![0i8; n];
    let mut q = vec![0i8; n];
    let got = format.decode(&bytes, 0, &mut i, &mut q).unwrap();
    assert_eq!(got, n);
    (i, q)
}

fn close(fixed: i32, exact: f64, bound: f64) -> bool {
    (f64::from(fixed) / 127.0 - exact).abs() <= bound
}

#[test]
fn correlator_equals_f64_reference_for_all_formats() {
    let formats = [
        (SampleFormat::Cs8, 0.0),
        (SampleFormat::Cs16 { shift: 0 }, 0.0),
        (SampleFormat::Int8, 4.1e6),
        (SampleFormat::SignMagnitude2 { complex: false }, 4.1e6),
        (SampleFormat::SignMagnitude2 { complex: true }, 0.0),
        (SampleFormat::Sign1, 4.1e6),
        (SampleFormat::Sign1Iq, 0.0),
        (SampleFormat::MultiChannel2 { channels: 3 }, 4.1e6),
    ];
    for (fi, &(format, fif)) in formats.iter().enumerate() {
        let fs = if fif > 0.0 { 16.368e6 } else { 2.6e6 };
        let n = 3 * (fs / 1000.0) as usize + 64;
        let cfg = CorrelatorConfig {
            sample_rate_hz: fs,
            intermediate_frequency_hz: fif,
            early_late_offset_chips: 0.5,
            slave_taps: gnss_attitude::signal::SlaveTaps::All,
        };
        let p = prn(7);
        let mut corr = Correlator::<3>::new(p, &cfg).unwrap();
        corr.set_carrier_frequency(fif + 1234.5).unwrap();
        corr.set_code_rate(1.023e6 * (1.0 + 1234.5 / 1575.42e6))
            .unwrap();
        corr.set_code_phase(100.3).unwrap();
        // Three antennas: three different sample streams.
        let ants: Vec<(Vec<i8>, Vec<i8>)> = (0..3)
            .map(|a| synth_samples(format, fs, fif, n, 10 * fi as u64 + a))
            .collect();
        let block = if format.is_complex() {
            SampleBlock::complex(
                0,
                [&ants[0].0[..], &ants[1].0[..], &ants[2].0[..]],
                [&ants[0].1[..], &ants[1].1[..], &ants[2].1[..]],
            )
            .unwrap()
        } else {
            SampleBlock::real(0, [&ants[0].0[..], &ants[1].0[..], &ants[2].0[..]]).unwrap()
        };
        let mut cursor = 0;
        let mut epochs: Vec<EpochCorrelations<3>> = Vec::new();
        // Feed in three uneven pieces to exercise resumption across calls.
        let _ = &block;
        let mut nco_at_start = vec![];
        while cursor < n {
            nco_at_start.push((cursor, corr.carrier(), corr.code()));
            if let Some(e) = corr.run(&block, &mut cursor).unwrap() {
                epochs.push(e);
            }
        }
        assert!(epochs.len() >= 3, "{format:?}: {} epochs", epochs.len());
        let quiet = f64::from(QUIET_OFFSET_CHIPS[6]) + 0.5;
        let mut max_rel = 0.0f64;
        for e in &epochs {
            let start = e.first_sample as usize;
            let &(_, carrier, code) = nco_at_start.iter().find(|(c, _, _)| *c == start).unwrap();
            for (a, (xi, xq)) in ants.iter().enumerate() {
                let xq = format.is_complex().then_some(&xq[..]);
                let r = reference_epoch(
                    xi,
                    xq,
                    start,
                    e.samples as usize,
                    carrier.phase,
                    carrier.step,
                    code.phase,
                    code.step,
                    p,
                    corr.early_late_offset_samples(),
                    quiet,
                );
                let bound = CARRIER_REPLICA_MAX_ERROR * r.sum_abs;
                let t = &e.taps[a];
                for (fixed, exact) in [
                    (t.early, r.early),
                    (t.prompt, r.prompt),
                    (t.late, r.late),
                    (t.noise, r.noise),
                ] {
                    assert!(
                        close(fixed.i, exact.0, bound) && close(fixed.q, exact.1, bound),
                        "{format:?} antenna {a}: fixed {fixed:?} vs {exact:?} (bound {bound})"
                    );
                    let err = (f64::from(fixed.i) / 127.0 - exact.0)
                        .abs()
                        .max((f64::from(fixed.q) / 127.0 - exact.1).abs());
                    max_rel = max_rel.max(err / r.sum_abs);
                }
            }
        }
        eprintln!(
            "{format:?}: max error / Σ|x| = {max_rel:.2e}, prompt[0] {:?}",
            epochs[1].taps[0].prompt
        );
        // The errors behave like a random walk, far inside the worst-case bound.
        assert!(
            max_rel < CARRIER_REPLICA_MAX_ERROR / 4.0,
            "{format:?}: {max_rel}"
        );
    }
}

/// Worst case for the accumulators: full-scale samples whose sign always agrees with the
/// replica, over the longest epoch the correlator accepts; compared with 64-bit sums.
#[test]
fn accumulators_do_not_overflow_at_the_largest_epoch() {
    let fs = MAX_SAMPLE_RATE_HZ;
    let cfg = CorrelatorConfig {
        sample_rate_hz: fs,
        intermediate_frequency_hz: 0.0,
        early_late_offset_chips: 0.5,
        slave_taps: gnss_attitude::signal::SlaveTaps::All,
    };
    let p = prn(3);
    let mut corr = Correlator::<1>::new(p, &cfg).unwrap();
    let rate = 1.023e6 * 0.99995;
    corr.set_code_rate(rate).unwrap();
    corr.set_carrier_frequency(1000.0).unwrap();
    corr.set_code_phase(0.0).unwrap();
    let n = corr.code().samples_to_wrap() as usize;
    assert!(n as u64 <= MAX_SAMPLES_PER_EPOCH && n > 63_000, "{n}");
    // Samples chosen so that every prompt product m_I · code is as large and positive as
    // possible: x_I = ±128/127 with the sign of c·code, x_Q with the sign of s·code.
    let (carrier, code) = (corr.carrier(), corr.code());
    let mut xi = vec![0i8; n + 10];
    let mut xq = vec![0i8; n + 10];
    let mut expected: i64 = 0;
    for k in 0..n {
        let ph = carrier
            .phase
            .wrapping_add((k as u32).wrapping_mul(carrier.step));
        let idx = (ph >> 24) as usize;
        let (c, s) = (i64::from(COS_TABLE[idx]), i64::from(SIN_TABLE[idx]));
        let chip = i64::from(p.chip(((code.phase + k as u64 * code.step) >> 32) as usize));
        let sgn = |v: i64| if v * chip >= 0 { -128i64 } else { 127 };
        // m_I·code = (x_I c + x_Q s)·code: pick x_I, x_Q to make it most negative.
        let (a, b) = (sgn(c), sgn(s));
        xi[k] = a as i8;
        xq[k] = b as i8;
        expected += (a * c + b * s) * chip;
    }
    let block = SampleBlock::complex(0, [&xi[..]], [&xq[..]]).unwrap();
    let mut cursor = 0;
    let e = corr
        .run(&block, &mut cursor)
        .unwrap()
        .expect("one full epoch");
    assert_eq!(e.samples as usize, n);
    assert!(
        expected.abs() > 1_200_000_000,
        "worst case reached: {expected}"
    );
    assert_eq!(i64::from(e.taps[0].prompt.i), expected);
}

// ---------------------------------------------------------------------------------------------
// Acquisition and tracking on synthesized three-antenna samples

use gnss_attitude::tracking::{Acquisition, AcquisitionConfig};
use host_sim::synth::quantize::{decode, encode, Quantizer, CS16_SHIFT};
use host_sim::synth::{AttitudeMotion, FrontEnd, Satellite, Scene};
use nalgebra::{Matrix3, Vector3};

/// Paper 003's array: equilateral triangle of side 1.5 m, origin at the middle of AB.
fn triangle() -> Vec<Vector3<f64>> {
    let l = 1.5;
    vec![
        Vector3::new(-l / 2.0, 0.0, 0.0),
        Vector3::new(l / 2.0, 0.0, 0.0),
        Vector3::new(0.0, l * 3f64.sqrt() / 2.0, 0.0),
    ]
}

fn scene(cn0: f64, prns: &[u8], seed: u64, fs: f64, complex: bool) -> Scene {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let satellites = prns
        .iter()
        .enumerate()
        .map(|(k, &p)| {
            let az: f64 = 0.8 * k as f64;
            let el: f64 = 0.3 + 0.15 * k as f64;
            Satellite {
                prn: p,
                cn0_dbhz: cn0,
                doppler_hz: rng.random_range(-4000.0..4000.0),
                doppler_rate_hz_s: rng.random_range(-0.8..0.8),
                code_phase_chips: rng.random_range(0.0..1023.0),
                carrier_phase_cycles: rng.random_range(0.0..1.0),
                los_ref: Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin()),
                data_seed: Some(seed + k as u64),
                track: None,
            }
        })
        .collect();
    Scene {
        satellites,
        antennas_b: triangle(),
        line_bias_cycles: vec![0.0, 0.1, -0.2],
        attitude: AttitudeMotion::Constant(Matrix3::identity()),
        front_end: FrontEnd {
            sample_rate_hz: fs,
            intermediate_frequency_hz: if complex { 0.0 } else { fs / 4.0 - 1000.0 },
            complex,
        },
        noise_seed: Some(seed ^ 0xabcdef),
    }
}

#[test]
fn acquisition_finds_visible_prns_and_no_false_ones() {
    for (cn0, seed) in [(35.0, 1u64), (40.0, 2), (45.0, 3)] {
        let visible = [3u8, 11, 19, 27];
        let sc = scene(cn0, &visible, seed, 2.6e6, true);
        let cfg = AcquisitionConfig {
            sample_rate_hz: 2.6e6,
            intermediate_frequency_hz: 0.0,
            doppler_max_hz: 5000.0,
            doppler_step_hz: 500.0,
            noncoherent_ms: 40,
            false_alarm_probability: 1e-3,
        };
        let n = cfg.samples_needed();
        let analog = sc.synthesize(0, n);
        let format = SampleFormat::Cs8;
        let planar = decode(format, &encode(format, &analog).unwrap(), 3, n).unwrap();
        let mut acq = Box::new(Acquisition::<2048>::new().unwrap());
        for p in [3u8, 11, 19, 27, 1, 8, 15, 30] {
            let r = acq
                .search(prn(p), &planar.i[0], Some(&planar.q[0]), 0, &cfg)
                .unwrap();
            if let Some(k) = visible.iter().position(|&v| v == p) {
                let truth = sc.truth(k, 0, 0.0);
                let code_err = (f64::from(r.code_phase_chips) - truth.code_phase_chips + 511.5)
                    .rem_euclid(1023.0)
                    - 511.5;
                let dopp_err = f64::from(r.doppler_hz) - truth.doppler_hz;
                eprintln!("{cn0} dB-Hz PRN {p}: metric {:.2} (threshold {:.2}), Doppler error {dopp_err:.0} Hz, code error {code_err:.3} chip", r.metric, r.threshold);
                assert!(r.detected, "{cn0} dB-Hz: PRN {p} missed");
                assert!(dopp_err.abs() <= 250.0 && code_err.abs() <= 0.5);
            } else {
                assert!(
                    !r.detected,
                    "{cn0} dB-Hz: false PRN {p} (metric {} > {})",
                    r.metric, r.threshold
                );
            }
        }
    }
}

/// CS16 and CS8 files (one per antenna) written, read back bit-exact, decoded and acquired;
/// also real 2-bit IF samples through the same path.
#[test]
fn sample_files_round_trip_and_acquire() {
    use host_sim::synth::file::{read_streams, write_streams};
    let dir = std::env::temp_dir().join(format!("gnss-attitude-signal-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cfg = |fs: f64, fif: f64| AcquisitionConfig {
        sample_rate_hz: fs,
        intermediate_frequency_hz: fif,
        doppler_max_hz: 5000.0,
        doppler_step_hz: 500.0,
        noncoherent_ms: 10,
        false_alarm_probability: 1e-3,
    };
    let cases = [
        (SampleFormat::Cs16 { shift: CS16_SHIFT }, 2.6e6, true),
        (SampleFormat::Cs8, 2.6e6, true),
        (
            SampleFormat::SignMagnitude2 { complex: false },
            16.368e6,
            false,
        ),
        (SampleFormat::MultiChannel2 { channels: 3 }, 16.368e6, false),
    ];
    for (k, (format, fs, complex)) in cases.into_iter().enumerate() {
        let sc = scene(45.0, &[9], 30 + k as u64, fs, complex);
        let c = cfg(fs, sc.front_end.intermediate_frequency_hz);
        let n = c.samples_needed() / 8 * 8 + 8;
        let streams = encode(format, &sc.synthesize(0, n)).unwrap();
        let paths = write_streams(&dir, &format!("case{k}"), format, &streams).unwrap();
        let back = read_streams(&paths).unwrap();
        assert_eq!(back, streams, "{format:?}");
        let planar = decode(format, &back, 3, n).unwrap();
        let mut acq = Box::new(Acquisition::<2048>::new().unwrap());
        let q = complex.then_some(&planar.q[0][..]);
        let r = acq.search(prn(9), &planar.i[0], q, 0, &c).unwrap();
        let truth = sc.truth(0, 0, 0.0);
        assert!(
            r.detected,
            "{format:?}: metric {} threshold {}",
            r.metric, r.threshold
        );
        assert!(
            (f64::from(r.doppler_hz) - truth.doppler_hz).abs() <= 250.0,
            "{format:?}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

use gnss_attitude::tracking::ChannelConfig;
use host_sim::chain::{run, ChainParams};

fn wrap_cycles(x: f64) -> f64 {
    x - x.round()
}

#[test]
fn tracking_holds_lock_and_recovers_phase_differences() {
    // CS8 complex baseband at 2.6 Msps, and the NT1065-style stream: real IF, one byte per
    // instant with the three antennas' 2-bit sign/magnitude samples, at 4.092 Msps (2-bit
    // quantization loses 0.55 dB, which the C/N0 and the phase bound must show).
    let nt1065 = SampleFormat::MultiChannel2 { channels: 3 };
    let cases = [
        (35.0, 11u64, SampleFormat::Cs8, 2.6e6, 0.0),
        (45.0, 12, SampleFormat::Cs8, 2.6e6, 0.0),
        (40.0, 13, nt1065, 4.092e6, 0.55),
    ];
    for (cn0, seed, format, fs, quantization_loss_db) in cases {
        let visible = [6u8, 13, 22];
        let complex = format.is_complex();
        let mut sc = scene(cn0, &visible, seed, fs, complex);
        let fif = sc.front_end.intermediate_frequency_hz;
        sc.attitude = AttitudeMotion::ConstantRate {
            c_rb0: Matrix3::identity(),
            omega_b: Vector3::new(0.0, 0.05, 0.0),
        };
        let params = ChainParams {
            scene: sc.clone(),
            format,
            quantizer: Quantizer::I8,
            acquisition: AcquisitionConfig {
                sample_rate_hz: fs,
                intermediate_frequency_hz: fif,
                doppler_max_hz: 5000.0,
                doppler_step_hz: 500.0,
                noncoherent_ms: 40,
                false_alarm_probability: 1e-3,
            },
            search_prns: visible.to_vec(),
            channel: ChannelConfig::new(fs, fif),
            duration_s: if complex { 3.0 } else { 2.5 },
            block: 40_920,
        };
        let out = run(&params, None).unwrap();
        assert_eq!(out.tracked.len(), 3);
        for t in &out.tracked {
            let last = t.epochs.last().unwrap();
            let locked_from = t.epochs.iter().position(|e| e.locked).unwrap();
            let after = &t.epochs[locked_from..];
            let mut err2 = 0.0;
            for e in after.iter().filter(|e| e.t > 1.0) {
                let (a, b) = (e.prompt[0], e.prompt[1]);
                let measured =
                    (b.1 * a.0 - b.0 * a.1).atan2(b.0 * a.0 + b.1 * a.1) / std::f64::consts::TAU;
                let truth = sc.truth(t.scene_index, 1, e.t).carrier_phase_cycles
                    - sc.truth(t.scene_index, 0, e.t).carrier_phase_cycles;
                err2 += wrap_cycles(measured - truth).powi(2);
            }
            let n = after.iter().filter(|e| e.t > 1.0).count() as f64;
            let rms = (err2 / n).sqrt();
            let bound =
                host_sim::stats::phase_difference_rms_cycles(cn0 - quantization_loss_db, 1e-3);
            eprintln!(
                "{cn0} dB-Hz PRN {}: locked at {:.2} s, all locked after: {}, C/N0 {:.1}, Doppler err {:.2} Hz, phase diff rms {rms:.4} cycles (bound {bound:.4})",
                t.acquisition.prn.number(),
                t.epochs[locked_from].t,
                after.iter().all(|e| e.locked),
                last.cn0_dbhz,
                last.doppler_hz - sc.truth(t.scene_index, 0, last.t).doppler_hz,
            );
            assert!(after.iter().all(|e| e.locked));
            assert!(
                (last.cn0_dbhz - (cn0 - quantization_loss_db)).abs() < 1.0,
                "{format:?}"
            );
            // Within the theoretical noise (10 % for the cross-correlation of the other two
            // satellites and the estimate's own spread over ~2 s).
            assert!(rms < 1.1 * bound, "{rms} vs {bound}");
            // Bit synchronization, and data bits every 20 ms once it is reached.
            let synced = t.epochs.iter().position(|e| e.bit_sync).expect("bit sync");
            let bits = t.epochs[synced..]
                .iter()
                .filter(|e| e.data_bit.is_some())
                .count();
            let expected = (t.epochs.len() - synced) / 20;
            assert!(
                bits + 1 >= expected && bits <= expected + 1,
                "{bits} bits, {expected} expected"
            );
        }
    }
}

/// The detection threshold against scipy's `gamma.isf(p, K, scale=1/K)` with
/// `p = −expm1(log1p(−P_fa)/M)` (K = 40 ms, M = 2048 · 41 cells).
#[test]
fn detection_threshold_matches_the_gamma_tail() {
    use gnss_attitude::tracking::acquisition::detection_threshold;
    for (pfa, scipy) in [
        (1e-3, 2.146_447_4),
        (1e-5, 2.347_116_1),
        (1e-6, 2.443_112_7),
    ] {
        let t = detection_threshold(40, 2048.0 * 41.0, pfa);
        assert!((f64::from(t) - scipy).abs() < 1e-4, "{pfa}: {t} vs {scipy}");
    }
}

/// LEO Dopplers: ±50 kHz search, a satellite at +41.3 kHz falling at 60 Hz/s, code Doppler
/// compensated across the non-coherent sum.
#[test]
fn acquisition_covers_leo_doppler() {
    let mut sc = scene(42.0, &[17], 21, 2.6e6, true);
    sc.satellites[0].doppler_hz = 41_300.0;
    sc.satellites[0].doppler_rate_hz_s = -60.0;
    let cfg = AcquisitionConfig {
        sample_rate_hz: 2.6e6,
        intermediate_frequency_hz: 0.0,
        doppler_max_hz: 50_000.0,
        doppler_step_hz: 500.0,
        noncoherent_ms: 10,
        false_alarm_probability: 1e-3,
    };
    let n = cfg.samples_needed();
    let format = SampleFormat::Cs8;
    let planar = decode(format, &encode(format, &sc.synthesize(0, n)).unwrap(), 3, n).unwrap();
    let mut acq = Box::new(Acquisition::<2048>::new().unwrap());
    let r = acq
        .search(prn(17), &planar.i[0], Some(&planar.q[0]), 0, &cfg)
        .unwrap();
    let truth = sc.truth(0, 0, 0.0);
    let code_err =
        (f64::from(r.code_phase_chips) - truth.code_phase_chips + 511.5).rem_euclid(1023.0) - 511.5;
    assert!(r.detected, "metric {} threshold {}", r.metric, r.threshold);
    assert!(
        (f64::from(r.doppler_hz) - truth.doppler_hz).abs() <= 250.0,
        "{}",
        r.doppler_hz
    );
    assert!(code_err.abs() <= 0.5, "{code_err}");
}

/// The exact phase-difference bound the scenario reports tends to the high-SNR formula
/// `1/(2π √((C/N0) T))` and exceeds it at low SNR.
#[test]
fn phase_difference_bound_matches_its_high_snr_limit() {
    use host_sim::stats::phase_difference_rms_cycles;
    let approx = |cn0: f64| 1.0 / (std::f64::consts::TAU * (10f64.powf(cn0 / 10.0) * 1e-3).sqrt());
    let high = phase_difference_rms_cycles(55.0, 1e-3);
    assert!(
        (high / approx(55.0) - 1.0).abs() < 0.01,
        "{high} vs {}",
        approx(55.0)
    );
    assert!(phase_difference_rms_cycles(35.0, 1e-3) > 1.1 * approx(35.0));
}

/// Prompt-only slaves: the reference antenna's taps and every prompt are those of the full
/// correlator, the slaves' other taps are zero.
#[test]
fn prompt_only_slaves_keep_the_prompts() {
    use gnss_attitude::signal::SlaveTaps;
    for (format, fs, fif) in [
        (SampleFormat::Cs8, 2.6e6, 0.0),
        (SampleFormat::Int8, 4.092e6, 1.0e6),
    ] {
        let n = 2 * (fs / 1000.0) as usize;
        let ants: Vec<(Vec<i8>, Vec<i8>)> = (0..3)
            .map(|a| synth_samples(format, fs, fif, n, 99 + a))
            .collect();
        let block = if format.is_complex() {
            SampleBlock::complex(
                0,
                [&ants[0].0[..], &ants[1].0[..], &ants[2].0[..]],
                [&ants[0].1[..], &ants[1].1[..], &ants[2].1[..]],
            )
            .unwrap()
        } else {
            SampleBlock::real(0, [&ants[0].0[..], &ants[1].0[..], &ants[2].0[..]]).unwrap()
        };
        let mut outs = Vec::new();
        for taps in [SlaveTaps::All, SlaveTaps::Prompt] {
            let cfg = CorrelatorConfig {
                sample_rate_hz: fs,
                intermediate_frequency_hz: fif,
                early_late_offset_chips: 0.5,
                slave_taps: taps,
            };
            let mut c = Correlator::<3>::new(prn(7), &cfg).unwrap();
            c.set_carrier_frequency(fif + 1234.5).unwrap();
            c.set_code_phase(100.3).unwrap();
            let mut cursor = 0;
            let mut last = None;
            while cursor < n {
                if let Some(e) = c.run(&block, &mut cursor).unwrap() {
                    last = Some(e);
                }
            }
            outs.push(last.unwrap());
        }
        let (all, prompt) = (&outs[0], &outs[1]);
        assert_eq!(all.taps[0], prompt.taps[0]);
        for a in 1..3 {
            assert_eq!(all.taps[a].prompt, prompt.taps[a].prompt);
            assert_eq!(prompt.taps[a].early, Default::default());
            assert_eq!(prompt.taps[a].noise, Default::default());
            assert_ne!(all.taps[a].early, Default::default());
        }
    }
}

/// LEO dynamics: Dopplers up to ±40 kHz and Doppler rates of 60–100 Hz/s at 36 dB-Hz. With
/// the refinement's rate estimate (`ChannelConfig::leo`) every channel locks within the ground
/// receiver's pull-in time (0.4 s at rate 0; 0.65 s allowed) and holds to the end, and the
/// Doppler follows the ramp. (Without it, the same channels lock between 0.5 and 2 s, or not
/// at all: printed for comparison.)
#[test]
fn tracking_holds_under_leo_doppler_rates() {
    let fs = 2.6e6;
    let visible = [4u8, 9, 14, 23, 27, 31];
    let mut sc = scene(36.0, &visible, 41, fs, true);
    let dynamics = [
        (38_000.0, 60.0),
        (-31_000.0, -100.0),
        (12_500.0, 80.0),
        (-39_500.0, -60.0),
        (24_000.0, 100.0),
        (-7_000.0, -80.0),
    ];
    for (s, (f, r)) in sc.satellites.iter_mut().zip(dynamics) {
        s.doppler_hz = f;
        s.doppler_rate_hz_s = r;
    }
    let mut params = ChainParams {
        scene: sc.clone(),
        format: SampleFormat::Cs8,
        quantizer: Quantizer::I8,
        acquisition: AcquisitionConfig {
            sample_rate_hz: fs,
            intermediate_frequency_hz: 0.0,
            doppler_max_hz: 50_000.0,
            doppler_step_hz: 500.0,
            noncoherent_ms: 40,
            false_alarm_probability: 1e-3,
        },
        search_prns: visible.to_vec(),
        channel: ChannelConfig::new(fs, 0.0),
        duration_s: 2.0,
        block: 32_768,
    };
    let lock_time = |t: &host_sim::chain::TrackedSatellite| {
        t.epochs
            .iter()
            .position(|e| e.locked)
            .map(|k| (k, t.epochs[k].t))
    };
    let unaided = run(&params, None).unwrap();
    params.channel = ChannelConfig::leo(fs, 0.0);
    let out = run(&params, None).unwrap();
    assert_eq!(out.tracked.len(), visible.len());
    for (t, u) in out.tracked.iter().zip(&unaided.tracked) {
        let (locked_from, lock_t) = lock_time(t).expect("lock");
        let tail: Vec<f64> = t
            .epochs
            .iter()
            .filter(|e| e.t > 1.5)
            .map(|e| e.doppler_hz - sc.truth(t.scene_index, 0, e.t).doppler_hz)
            .collect();
        let rms = (tail.iter().map(|d| d * d).sum::<f64>() / tail.len() as f64).sqrt();
        eprintln!(
            "PRN {}: rate {} Hz/s, locked at {lock_t:.2} s (without the rate estimate: {:?}), Doppler error RMS (last 0.5 s) {rms:.2} Hz",
            t.acquisition.prn.number(),
            sc.satellites[t.scene_index].doppler_rate_hz_s,
            lock_time(u).map(|(_, s)| s),
        );
        assert!(lock_t < 0.65, "locked only at {lock_t} s");
        assert!(t.epochs[locked_from..].iter().all(|e| e.locked));
        assert!(rms < 5.0, "{rms}");
    }
}
