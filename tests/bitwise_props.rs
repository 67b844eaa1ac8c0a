//! Property tests: the bit-parallel correlator equals its scalar reference bit for bit on
//! random planes, random NCO phases and steps (fast and general carrier paths, code rates up
//! to 1 % off nominal), random block lengths (code-period wraps and span edges anywhere inside
//! words), 1- and 2-bit samples, complex and real, 2- and 3-level carriers, both tap sets;
//! with one scratch shared by two correlators that run in turn, as a receiver's channels do.
//! A correlator built with the complex 2-level kernels only (firmware `realtime`'s) gives the
//! same results where its kernels serve and refuses the other formats.

use gnss_attitude::signal::bitwise::{
    AntennaPlanes, BitBlock, BitCorrelator, BitCorrelatorConfig, BitCorrelatorError, BitScratch,
    CarrierLevels, CodeTable, PlaneFormat, Resolution, ScalarReference, COMPLEX_TWO_LEVEL_KERNELS,
};
use gnss_attitude::signal::{CorrelatorConfig, Prn, SlaveTaps};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[derive(Clone, Debug)]
struct Case {
    seed: u64,
    prn: u8,
    fs: f64,
    complex: bool,
    two_bit: bool,
    three: bool,
    prompt_only: bool,
    early_late_chips: f32,
    carrier_hz: f64,
    code_rate_offset: f64,
    code_phase: f64,
    carrier_phase: f64,
    blocks: Vec<usize>,
}

fn case() -> impl Strategy<Value = Case> {
    let rates = prop_oneof![
        Just(2.046e6),
        Just(2.6e6),
        Just(4.092e6),
        Just(16.368e6),
        2.046e6..20.0e6f64
    ];
    (
        any::<u64>(),
        1u8..=32,
        rates,
        any::<(bool, bool, bool, bool)>(),
        0.05f32..1.0,
        (
            -0.4999f64..0.4999,
            prop_oneof![Just(0.0), -0.002f64..0.002, -0.25f64..0.25],
        ),
        prop_oneof![Just(0.0), -1e-4f64..1e-4, -0.0099f64..0.0099],
        (prop_oneof![1015.0f64..1023.0, 0.0f64..1023.0], 0.0f64..1.0),
        prop::collection::vec(prop_oneof![1usize..40, 1usize..3000], 1..12),
    )
        .prop_map(
            |(
                seed,
                prn,
                fs,
                (complex, two_bit, three, prompt_only),
                el,
                (f, near),
                co,
                (cp, kp),
                blocks,
            )| {
                // Near a multiple of f_s/4 (the fast carrier path) or anywhere (general path).
                let quarter = (f * 4.0).round() / 4.0;
                let carrier = if near != 0.0 { quarter + near } else { f };
                Case {
                    seed,
                    prn,
                    fs,
                    complex,
                    two_bit,
                    three,
                    prompt_only,
                    early_late_chips: el,
                    carrier_hz: carrier.clamp(-0.4999, 0.4999) * fs,
                    code_rate_offset: co,
                    code_phase: cp,
                    carrier_phase: kp,
                    blocks,
                }
            },
        )
}

fn planes(rng: &mut ChaCha8Rng, len: usize) -> [Vec<u32>; 4] {
    let words = len.div_ceil(32);
    core::array::from_fn(|_| {
        let mut v: Vec<u32> = (0..words).map(|_| rng.random()).collect();
        if !len.is_multiple_of(32) {
            if let Some(last) = v.last_mut() {
                *last &= (1u32 << (len % 32)) - 1;
            }
        }
        v
    })
}

fn run_case(c: &Case) -> Result<usize, TestCaseError> {
    let mut rng = ChaCha8Rng::seed_from_u64(c.seed);
    let format = PlaneFormat {
        resolution: if c.two_bit {
            Resolution::TwoBit
        } else {
            Resolution::OneBit
        },
        complex: c.complex,
    };
    let config = BitCorrelatorConfig {
        correlator: CorrelatorConfig {
            sample_rate_hz: c.fs,
            intermediate_frequency_hz: 0.0,
            early_late_offset_chips: c.early_late_chips,
            slave_taps: if c.prompt_only {
                SlaveTaps::Prompt
            } else {
                SlaveTaps::All
            },
        },
        format,
        carrier: if c.three {
            CarrierLevels::Three
        } else {
            CarrierLevels::Two
        },
    };
    let prn = Prn::new(c.prn).unwrap();
    let table = CodeTable::new(c.fs).unwrap();
    let mut fast = BitCorrelator::<3>::new(prn, &config).unwrap();
    let mut slow = ScalarReference::<3>::new(prn, &config).unwrap();
    fast.set_carrier_frequency(c.carrier_hz).unwrap();
    fast.set_code_rate(1.023e6 * (1.0 + c.code_rate_offset))
        .unwrap();
    fast.set_code_phase(c.code_phase).unwrap();
    fast.set_carrier_phase(c.carrier_phase).unwrap();
    slow.carrier = fast.carrier();
    slow.code = fast.code();
    slow.carrier_total = fast.carrier_phase_total();
    let lean_serves = c.complex && !c.three;
    let mut lean = match BitCorrelator::<3, COMPLEX_TWO_LEVEL_KERNELS>::new(prn, &config) {
        Ok(mut lean) => {
            prop_assert!(lean_serves, "built without its kernel: {:?}", c);
            lean.set_nco_steps(fast.carrier().step, fast.code().step)
                .unwrap();
            lean.set_code_phase(c.code_phase).unwrap();
            lean.set_carrier_phase(c.carrier_phase).unwrap();
            prop_assert_eq!(lean.code(), fast.code());
            prop_assert_eq!(lean.carrier(), fast.carrier());
            Some(lean)
        }
        Err(e) => {
            prop_assert!(!lean_serves, "refused: {:?}", c);
            prop_assert_eq!(e, BitCorrelatorError::KernelNotBuilt);
            None
        }
    };
    // Another satellite's correlator on the same blocks, run before each call with the same
    // scratch: what it leaves there must not reach the results.
    let mut other = BitCorrelator::<3>::new(Prn::new(c.prn % 32 + 1).unwrap(), &config).unwrap();
    other.set_carrier_frequency(-0.5 * c.carrier_hz).unwrap();
    other.set_code_phase(1022.0 - c.code_phase).unwrap();
    let mut scratch = BitScratch::new();
    let mut first = 0u64;
    let mut outputs = 0;
    for &len in &c.blocks {
        let p: Vec<[Vec<u32>; 4]> = (0..3).map(|_| planes(&mut rng, len)).collect();
        let ant: Vec<AntennaPlanes<'_>> = p
            .iter()
            .map(|x| AntennaPlanes::new(format, len, &x[0], &x[1], &x[2], &x[3]).unwrap())
            .collect();
        let block = BitBlock::new(first, &table, [ant[0], ant[1], ant[2]]).unwrap();
        let (mut cf, mut cs, mut co, mut cl) = (0usize, 0usize, 0usize, 0usize);
        // Bounded: each call advances the cursor or returns None at the block end.
        for _ in 0..64 {
            other.run_in(&block, &mut co, &mut scratch).unwrap();
            let a = fast.run_in(&block, &mut cf, &mut scratch).unwrap();
            let b = slow.run(&block, &mut cs).unwrap();
            prop_assert_eq!(cf, cs);
            prop_assert_eq!(a, b, "case {:?}", c);
            prop_assert_eq!(fast.code(), slow.code);
            prop_assert_eq!(fast.carrier(), slow.carrier);
            prop_assert_eq!(fast.carrier_phase_total(), slow.carrier_total);
            if let Some(lean) = lean.as_mut() {
                prop_assert_eq!(lean.run_in(&block, &mut cl, &mut scratch).unwrap(), a);
                prop_assert_eq!(cl, cf);
            }
            if a.is_some() {
                outputs += 1;
                // Steer the NCOs between epochs as a tracking loop would.
                let df: f64 = rng.random_range(-50.0..50.0);
                let f = (c.carrier_hz + df).clamp(-0.4999 * c.fs, 0.4999 * c.fs);
                fast.set_carrier_frequency(f).unwrap();
                slow.carrier = fast.carrier();
                if let Some(lean) = lean.as_mut() {
                    lean.set_carrier_frequency(f).unwrap();
                }
            }
            if cf == len {
                break;
            }
        }
        first += len as u64;
    }
    Ok(outputs)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, .. ProptestConfig::default() })]

    #[test]
    fn bit_parallel_equals_scalar_reference(c in case()) {
        let outputs = run_case(&c)?;
        let samples: usize = c.blocks.iter().sum();
        eprintln!("samples {samples} outputs {outputs}");
    }
}

/// Long runs through several whole epochs at the target's case (2.6 Msps complex, 1 ms blocks
/// not aligned to the code period) for all eight variants.
#[test]
fn whole_epochs_equal_the_reference_for_all_variants() {
    for variant in 0..16u32 {
        let c = Case {
            seed: 100 + u64::from(variant),
            prn: 5 + variant as u8,
            fs: 2.6e6,
            complex: variant & 1 != 0,
            two_bit: variant & 2 != 0,
            three: variant & 4 != 0,
            prompt_only: variant & 8 != 0,
            early_late_chips: 0.5,
            carrier_hz: if variant & 1 != 0 {
                2345.0
            } else {
                650_000.0 - 1234.0
            },
            code_rate_offset: 3e-5,
            code_phase: 1000.3,
            carrier_phase: 0.3,
            blocks: vec![2600, 2600, 2601, 17, 2583, 2600],
        };
        let outputs = run_case(&c).unwrap();
        assert!(outputs >= 5, "variant {variant}: {outputs} epochs");
    }
}
