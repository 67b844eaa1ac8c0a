//! The 2- and 1-bit front ends (`host-sim run --front-end sm2|bit1`) against CS8 on the same
//! synthesized signals: the tracking channels' C/N0 drops by about the quantization loss, and
//! the open-loop correlator experiment ([`host_sim::open_loop`]) measures the sample and the
//! bit-parallel carrier quantization losses near their theoretical values.
//!
//! Both tests run in debug builds in about 20 s together (`cargo test -p host-sim --test
//! front_end`); the full-length figures come from `host-sim run signal --front-end bit1`.

use host_sim::chain::{self, ChainParams};
use host_sim::open_loop::open_loop_losses;
use host_sim::scenarios::signal::{cn0_after_lock, cn0_loss_db, mean_cn0, params};
use host_sim::synth::quantize::Quantizer;

/// Seconds tracked: lock from about 1 s, C/N0 averaged over the locked epochs from 2 s on.
const SECONDS: f64 = 4.5;

/// The `signal` scenario's eight satellites at 40 dB-Hz for [`SECONDS`], searching only the
/// scene's PRNs (the test is about tracking, not the search), through `quantizer`.
fn short_signal(quantizer: Quantizer, seed: u64) -> ChainParams {
    let mut p = params(40.0, seed, SECONDS);
    p.search_prns = p.scene.satellites.iter().map(|s| s.prn).collect();
    p.quantizer = quantizer;
    p
}

/// Theory (Van Vleck, Spilker): 1-bit 1.96 dB, 2-bit (±1, ±3, threshold 1σ) 0.55 dB at low
/// per-sample SNR. Over 2.5 s of eight satellites the C/N0 estimates of the two runs (which
/// share the thermal noise) differ by the loss to about 0.1 dB. The channels of a 2- or 1-bit
/// front end run the bit-parallel correlator with the 3-level carrier (`host_sim::chain`), so
/// the loss is the samples' and the carrier's: 0.88 and 2.23 dB with this seed (0.53 and
/// 1.90 dB with the `i8` correlator on the quantized values, before the bit-parallel path). The
/// bands (1.2–3.0 dB, 0.2–1.2 dB, issue 18's targets as upper ends) fail if the quantizer is
/// missing (0 dB) or the wrong one (a 1-bit quantizer in place of the 2-bit one, or the
/// reverse), and the measured loss must agree with the bit path's theory
/// ([`Quantizer::bit_path_theory_loss_db`]: 0.90 / 2.31 dB) within 0.3 dB.
#[test]
fn quantized_front_ends_lower_the_tracked_cn0_by_the_quantization_loss() {
    let seed = 5;
    let run = |q: Quantizer| {
        let out = chain::run(&short_signal(q, seed), None).unwrap();
        assert_eq!(out.tracked.len(), 8, "{q}: every satellite tracked");
        cn0_after_lock(&out)
    };
    let reference = run(Quantizer::I8);
    assert_eq!(reference.len(), 8, "every satellite locked on CS8");
    for (q, band) in [(Quantizer::Sm2, 0.2..1.2), (Quantizer::Bit1, 1.2..3.0)] {
        let own = run(q);
        let loss = cn0_loss_db(&reference, &own).unwrap();
        eprintln!(
            "{q}: C/N0 after lock {:.2} dB-Hz (CS8 {:.2}), loss {loss:.2} dB over {} satellites",
            mean_cn0(&own),
            mean_cn0(&reference),
            own.len()
        );
        assert!(
            band.contains(&loss),
            "{q}: loss {loss:.2} dB outside {band:?}"
        );
        let theory = q.bit_path_theory_loss_db();
        assert!(
            (loss - theory).abs() < 0.3,
            "{q}: measured {loss:.2} dB, the bit path's theory {theory:.2} dB"
        );
    }
}

/// The open-loop experiment at 40 dB-Hz over 1000 epochs: sample quantization within 0.3 dB
/// of 0.55 dB (2-bit) and 1.96 dB (1-bit); the bit-parallel correlator's carrier quantization
/// on the same quantized samples within 0.3 dB of 0.91 dB (2-level: the quadrant signs,
/// 8/π²) and 0.35 dB (3-level). The SNR estimator scatters by about 0.08 dB per path at
/// 1000 epochs on three antennas; the tolerance is about four of those.
#[test]
fn open_loop_losses_of_the_bit_parallel_paths_follow_theory() {
    for (q, sample_theory) in [(Quantizer::Sm2, 0.55), (Quantizer::Bit1, 1.96)] {
        let l = open_loop_losses(q, 40.0, 7, 1000).unwrap();
        eprintln!(
            "{q}: samples {:.3} dB (theory {sample_theory}), carrier 2-level {:.3} dB (0.91), 3-level {:.3} dB (0.35), {} epochs",
            l.open_loop_sample_loss_db,
            l.open_loop_carrier_loss_db_2level,
            l.open_loop_carrier_loss_db_3level,
            l.open_loop_epochs
        );
        assert!(l.open_loop_epochs >= 990, "{} epochs", l.open_loop_epochs);
        let near = |x: f64, t: f64| (x - t).abs() < 0.3;
        assert!(
            near(l.open_loop_sample_loss_db, sample_theory),
            "{q} samples"
        );
        assert!(
            near(l.open_loop_carrier_loss_db_2level, 0.91),
            "{q} 2-level"
        );
        assert!(
            near(l.open_loop_carrier_loss_db_3level, 0.35),
            "{q} 3-level"
        );
    }
}

/// `i8` is the reference: nothing to compare in the open loop.
#[test]
fn the_open_loop_experiment_refuses_the_i8_front_end() {
    assert!(open_loop_losses(Quantizer::I8, 40.0, 1, 10).is_err());
}

/// The command-line names round-trip and an unknown one is refused.
#[test]
fn front_end_names_parse() {
    for q in Quantizer::ALL {
        assert_eq!(Quantizer::parse(q.name()).unwrap(), q);
    }
    assert!(Quantizer::parse("cs16").is_err());
}
