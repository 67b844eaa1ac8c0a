//! The main job's sample-level stretch carries the LNAV message and its receiver decodes it:
//! the synthesized samples carry the encoder's bits at the signal time each left the
//! satellite, the core's bit synchronizer and subframe synchronizer run on the tracking
//! channels' 1 ms prompts, and what they decode goes to the flight's navigation store. Heavy
//! (25 s from samples, about 40 s in release): run it with `--ignored`.

use host_sim::scenarios::microsat::run::{fly, FlightConfig};
use host_sim::scenarios::microsat::short;
use host_sim::synth::lnav::LnavEncoder;

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
    prns.dedup();
    prns.sort_unstable();
    prns.dedup();
    assert!(prns.len() >= 4, "decoded from {prns:?}");

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
