//! The main job's sample-level stretch carries the LNAV message and its receiver decodes it:
//! the synthesized samples carry the encoder's bits at the signal time each left the
//! satellite, the core's bit synchronizer and subframe synchronizer run on the tracking
//! channels' 1 ms prompts, and what they decode goes to the flight's navigation store; with
//! the channels' code phases the decoded subframes give the time of transmission (seed 1: 33
//! seconds×channels, 0.97 m RMS, 2.4 m worst against the truth). Heavy (25 s from samples,
//! about 20 s in release): run it with `--ignored`.

use host_sim::scenarios::microsat::navigation::Navigation;
use host_sim::scenarios::microsat::run::{fly, FlightConfig};
use host_sim::scenarios::microsat::sample_level::chain_params;
use host_sim::scenarios::microsat::short;
use host_sim::scenarios::microsat::world::World;
use host_sim::synth::lnav::{LnavEncoder, SUBFRAME_S};
use host_sim::synth::scene::{CHIP_RATE, SPEED_OF_LIGHT};

/// Bits of a 24-bit data word the encoder leaves at zero for the parity to solve (bits 23–24
/// of the HOW and of word 10), set by the signal; not part of the message.
const PARITY_SOLVING_BITS: u32 = 0b11;

#[test]
#[ignore = "heavy: cargo test --release -p host-sim --test sample_level_lnav -- --ignored"]
fn the_sample_level_stretch_decodes_the_subframes_the_encoder_wrote() {
    let config = FlightConfig {
        duration_s: 25.0,
        sample_level_s: 25.0,
        ..short(1)
    };
    let record = fly(&config, None).unwrap();
    let nav = &record.navigation;
    let stats = record
        .sample_stats
        .as_ref()
        .expect("a sample-level stretch");

    // every satellite found locks within ~2 s, synchronizes on its bits within ~1 s and on
    // a preamble confirmed by the next one within two subframes (≤ 12 s): by 25 s each has
    // given a subframe or two
    assert!(stats.detections >= 4, "{stats:?}");
    assert_eq!(
        nav.sample_level_subframes as usize,
        nav.sample_level_decoded.len()
    );
    assert!(
        nav.sample_level_subframes as usize >= stats.detections,
        "{} subframes from {} channels",
        nav.sample_level_subframes,
        stats.detections
    );
    assert_eq!(nav.sample_level_parity_failures, 0);
    let mut prns: Vec<u8> = nav.sample_level_decoded.iter().map(|d| d.0).collect();
    prns.sort_unstable();
    prns.dedup();
    assert!(prns.len() >= 4, "decoded from {prns:?}");

    // the channels' code phases with their decoded subframes give the time of transmission
    // (the core's `TransmitTime`): each second of each synchronized channel, c·Δt against the
    // truth
    let errors = &nav.sample_level_code_errors_m;
    let rms = (errors.iter().map(|e| e * e).sum::<f64>() / errors.len().max(1) as f64).sqrt();
    let worst = errors.iter().copied().map(f64::abs).fold(0.0, f64::max);
    eprintln!(
        "code-phase times of transmission: {} of them, RMS {rms:.2} m, worst {worst:.2} m",
        errors.len()
    );
    assert!(errors.len() >= 2 * prns.len(), "{} errors", errors.len());
    assert!(rms < 5.0 && worst < 20.0, "RMS {rms} m, worst {worst} m");

    // what was decoded is what the encoder wrote for that satellite and subframe time:
    // random data bits, a wrong signal time or a slipped bit would fail the comparison
    let encoder = LnavEncoder::bundled();
    for (prn, sf) in &nav.sample_level_decoded {
        let start = sf.start_tow_s();
        let written = encoder
            .subframe_words(*prn, encoder.almanac_week, start)
            .expect("a PRN of the almanac");
        for (w, (got, want)) in sf.words.iter().zip(written).enumerate() {
            let mask = if w == 1 || w == 9 {
                !PARITY_SOLVING_BITS
            } else {
                u32::MAX
            };
            assert_eq!(
                got & mask,
                want & mask,
                "PRN {prn} subframe at TOW {start} s, word {}: {got:06x} vs {want:06x}",
                w + 1
            );
        }
    }
}

/// The stretch's code carries the time of transmission: at the reference antenna the scene's
/// code count is `CHIP_RATE·(t_sv − reference)`, `t_sv` the signal time the navigation's
/// truth gives (light time, Sagnac, satellite clock), `reference` the subframe start before
/// the first sample's. Left over: antenna A's offset from the array origin (`μ·r_A`, below
/// 0.3 m) and the 10 ms table's interpolation (millimetres): 0.003 chip (0.9 m) bounds both.
/// A geometric range without the satellite clock (up to ~1 ms, 300 km) or without light time
/// would be thousands of chips off.
#[test]
fn the_stretch_code_phase_is_the_time_of_transmission() {
    let c = short(1);
    let world = World::new(c.motion, c.u0, c.gps_offset_s, c.detumble_rates);
    let nav = Navigation::new(&world, 7).unwrap();
    let params = chain_params(&world, &nav, 3.0, 1, &[]);
    assert!(params.scene.satellites.len() >= 4);
    let mut worst = 0.0f64;
    for (k, sat) in params.scene.satellites.iter().enumerate() {
        let t_sv = |t: f64| {
            let s = nav
                .signal(&world, sat.prn, t)
                .expect("an almanac satellite");
            s.transmit_s + s.clock_s
        };
        let reference = (t_sv(0.0) / SUBFRAME_S).floor() * SUBFRAME_S;
        for t in [0.0, 0.013, 1.0, 2.507] {
            let chips = params.scene.truth(k, 0, t).code_chips_total;
            let want = CHIP_RATE * (t_sv(t) - reference);
            worst = worst.max((chips - want).abs());
        }
    }
    assert!(
        worst < 0.003,
        "code count off the time of transmission by {worst} chips ({} m)",
        worst / CHIP_RATE * SPEED_OF_LIGHT
    );
}
