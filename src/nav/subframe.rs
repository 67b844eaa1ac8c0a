//! Subframe synchronization: the LNAV preamble `10001011` in either polarity, then the parity
//! of all ten words (IS-GPS-200 20.3.5), then the HOW (time of week, subframe id).
//!
//! The synchronizer keeps the last 302 bits (a subframe and the two bits before it, `D29*`,
//! `D30*` of the previous word 10) in a 320-bit shift register.
//!
//! * **Searching**: at every bit whose window starts with the preamble or its complement, it
//!   checks the parity of the ten words (each with `D29*`, `D30*` of the word before it, as
//!   received, so both polarities decode to the same data) and the HOW's subframe id. A window
//!   that fails is data that happens to look like a preamble (runs of zeros pass the parity at
//!   any alignment, so a failure while searching says nothing) and is not reported.
//! * **Confirming** (after a window that decoded): the window is held, not reported, until the
//!   window 300 bits later also decodes, in the same polarity, with the next time of week. A
//!   preamble inside the data whose ten words happen to pass the parity (structured data such
//!   as reserved pages does) never reaches the caller. Once confirmed, both subframes are
//!   reported: the held one at once, the newer one at the next bit.
//! * **Synchronized** (after a confirmed pair): only the window 300 bits later is decoded,
//!   whatever its bits; a failure there is a real subframe refused
//!   ([`SubframeError::Parity`], [`SubframeError::Preamble`]), reported for the caller to
//!   count, and the synchronizer goes back to searching.

use super::bits::{DataBit, EPOCHS_PER_BIT};
use super::parity::{decode_word, ParityError};
use super::{SUBFRAME_S, WEEK_S};

/// Bits per subframe.
pub const SUBFRAME_BITS: u64 = 300;
/// The preamble of the TLM word.
pub const PREAMBLE: u32 = 0b1000_1011;
/// Bits held: a subframe and `D29*`, `D30*` before it.
const WINDOW_BITS: u16 = 302;

/// Error returned by [`SubframeSync::push`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum SubframeError {
    /// The subframe at the expected boundary has a word whose parity fails; the subframe is
    /// dropped.
    #[error("word {word} failed its parity check")]
    Parity {
        /// The failing word, 1–10.
        word: u8,
        /// The parity check's result.
        #[source]
        source: ParityError,
    },
    /// The words at the expected subframe start passed their parity but the first is not
    /// the preamble (the bit stream slipped).
    #[error("no preamble at the expected subframe start")]
    Preamble,
    /// The HOW passed its parity but names no LNAV subframe (id outside 1–5).
    #[error("subframe id {id} is not 1-5")]
    InvalidId {
        /// The id found.
        id: u8,
    },
}

impl crate::error::Error for SubframeError {
    fn kind(&self) -> crate::error::ErrorKind {
        crate::error::ErrorKind::InvalidInput
    }
}

/// One decoded subframe.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Subframe {
    /// The 24 data bits of each word (parity removed, complemented words and polarity
    /// corrected), word 1 (TLM) first; bit 1 of a word is bit 23 of its value.
    pub words: [u32; 10],
    /// Epoch (code period) at which the subframe's first bit started.
    pub start_epoch: u64,
    /// Whether the bit stream was received inverted (Costas 180° ambiguity).
    pub inverted: bool,
}

impl Subframe {
    /// The HOW's truncated time-of-week count (17 bits, units of 6 s): the time of the start
    /// of the *next* subframe.
    pub fn tow_count(&self) -> u32 {
        self.words[1] >> 7
    }

    /// Subframe id (1–5) from HOW bits 20–22.
    pub fn id(&self) -> u8 {
        ((self.words[1] >> 2) & 0b111) as u8
    }

    /// Alert flag (HOW bit 18): the satellite's URA may be worse than indicated.
    pub fn alert(&self) -> bool {
        (self.words[1] >> 6) & 1 == 1
    }

    /// Anti-spoof flag (HOW bit 19).
    pub fn anti_spoof(&self) -> bool {
        (self.words[1] >> 5) & 1 == 1
    }

    /// GPS time of week at the start of this subframe, s (a multiple of 6): the HOW's count
    /// × 6 s minus one subframe, modulo a week.
    pub fn start_tow_s(&self) -> u32 {
        let week = WEEK_S as u32;
        let next = self.tow_count().saturating_mul(SUBFRAME_S as u32) % week;
        (next + week - SUBFRAME_S as u32) % week
    }
}

/// Subframe synchronization on a stream of data bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SubframeSync {
    register: [u64; 5],
    held: u16,
    last_start: Option<u64>,
    expected_start: Option<u64>,
    /// A decoded window waiting for the next one to confirm it.
    candidate: Option<Subframe>,
    /// A confirmed subframe reported at the next bit.
    queued: Option<Subframe>,
}

impl Default for SubframeSync {
    fn default() -> Self {
        Self::new()
    }
}

impl SubframeSync {
    /// An empty synchronizer.
    pub fn new() -> Self {
        Self {
            register: [0; 5],
            held: 0,
            last_start: None,
            expected_start: None,
            candidate: None,
            queued: None,
        }
    }

    /// Forgets the bits held (after a break in the bit stream).
    pub fn reset(&mut self) {
        *self = Self::new();
    }

    /// Whether the last subframe decoded and was confirmed, and the next is expected 300 bits
    /// later.
    pub fn synchronized(&self) -> bool {
        self.expected_start.is_some() && self.candidate.is_none()
    }

    /// Takes the next data bit; returns a subframe when this bit completed one (or, after a
    /// confirmation, the confirming subframe one bit late).
    ///
    /// A bit that does not follow the previous one by one bit (20 epochs) restarts the
    /// window.
    ///
    /// # Errors
    /// At the expected boundary of a synchronized stream: [`SubframeError::Parity`],
    /// [`SubframeError::Preamble`], [`SubframeError::InvalidId`]; the synchronizer returns
    /// to searching, the bits stay held.
    pub fn push(&mut self, bit: &DataBit) -> Result<Option<Subframe>, SubframeError> {
        let waiting = self.queued.take();
        match (self.push_bit(bit), waiting) {
            (Ok(None), Some(confirmed)) => Ok(Some(confirmed)),
            (result, waiting) => {
                // (a boundary cannot fall on the bit after a confirmation; kept, not lost)
                self.queued = self.queued.or(waiting);
                result
            }
        }
    }

    fn push_bit(&mut self, bit: &DataBit) -> Result<Option<Subframe>, SubframeError> {
        let follows = self
            .last_start
            .is_some_and(|s| bit.start_epoch == s.saturating_add(EPOCHS_PER_BIT));
        if !follows {
            self.register = [0; 5];
            self.held = 0;
            self.expected_start = None;
            self.candidate = None;
        }
        self.last_start = Some(bit.start_epoch);
        self.shift_in(bit.value);
        if self.held < WINDOW_BITS {
            return Ok(None);
        }
        let Some(start_epoch) = bit
            .start_epoch
            .checked_sub((SUBFRAME_BITS - 1) * EPOCHS_PER_BIT)
        else {
            return Ok(None);
        };
        if let Some(expected) = self.expected_start {
            // synchronized or confirming: only the expected boundary counts
            if start_epoch != expected {
                return Ok(None);
            }
            if let Some(candidate) = self.candidate.take() {
                return Ok(self.confirm(candidate, start_epoch));
            }
            return match self.decode_window(start_epoch) {
                Ok(subframe) => {
                    self.expected_start = Some(next_start(start_epoch));
                    Ok(Some(subframe))
                }
                Err(err) => {
                    self.expected_start = None;
                    Err(err)
                }
            };
        }
        self.search(start_epoch);
        Ok(None)
    }

    /// Searching: a window that starts with the preamble in either polarity and decodes
    /// becomes the candidate, to be confirmed 300 bits later.
    fn search(&mut self, start_epoch: u64) {
        let raw_preamble = self.window_bits(0, 8);
        if raw_preamble != PREAMBLE && raw_preamble != (!PREAMBLE & 0xFF) {
            return;
        }
        if let Ok(subframe) = self.decode_window(start_epoch) {
            self.candidate = Some(subframe);
            self.expected_start = Some(next_start(start_epoch));
        }
    }

    /// Confirming: the window 300 bits after `candidate` confirms it if it decodes in the same
    /// polarity with the next time of week; then the candidate is returned and this window
    /// queued. Otherwise the candidate was data that looked like a subframe: it is dropped
    /// and this window searched as any other.
    fn confirm(&mut self, candidate: Subframe, start_epoch: u64) -> Option<Subframe> {
        self.expected_start = None;
        match self.decode_window(start_epoch) {
            Ok(next) if follows_in_time(&candidate, &next) => {
                self.expected_start = Some(next_start(start_epoch));
                self.queued = Some(next);
                Some(candidate)
            }
            _ => {
                self.search(start_epoch);
                None
            }
        }
    }

    fn shift_in(&mut self, value: bool) {
        for i in (1..self.register.len()).rev() {
            let carry = self.register.get(i - 1).map_or(0, |w| w >> 63);
            if let Some(w) = self.register.get_mut(i) {
                *w = (*w << 1) | carry;
            }
        }
        self.register[0] = (self.register[0] << 1) | u64::from(value);
        self.held = self.held.saturating_add(1).min(WINDOW_BITS);
    }

    /// Received bit `k` bits before the newest (`k = 0` newest).
    fn bit_back(&self, k: u64) -> bool {
        let word = self.register.get((k / 64) as usize).copied().unwrap_or(0);
        (word >> (k % 64)) & 1 == 1
    }

    /// `len ≤ 32` received bits of the window starting at subframe bit `first` (0-based,
    /// bit 0 = first bit of the subframe; −1 and −2 are `D30*`, `D29*`), first bit most
    /// significant.
    fn window_bits(&self, first: i64, len: u32) -> u32 {
        let mut out = 0u32;
        for i in 0..i64::from(len.min(32)) {
            // (small bit positions; saturating: the bounds are visible)
            let j = first.saturating_add(i);
            let k = (SUBFRAME_BITS as i64 - 1).saturating_sub(j).max(0) as u64;
            out = (out << 1) | u32::from(self.bit_back(k));
        }
        out
    }

    /// Decodes the ten words.
    fn decode_window(&self, start_epoch: u64) -> Result<Subframe, SubframeError> {
        let mut words = [0u32; 10];
        let stars = self.window_bits(-2, 2);
        let inverted = stars & 1 == 1;
        let (mut d29, mut d30) = (stars & 0b10 != 0, stars & 1 != 0);
        for (w, out) in words.iter_mut().enumerate() {
            let raw = self.window_bits(30 * w as i64, 30);
            let number = w as u8 + 1;
            *out = decode_word(raw, d29, d30).map_err(|source| SubframeError::Parity {
                word: number,
                source,
            })?;
            d29 = raw & 0b10 != 0;
            d30 = raw & 1 != 0;
        }
        if words[0] >> 16 != PREAMBLE {
            return Err(SubframeError::Preamble);
        }
        let subframe = Subframe {
            words,
            start_epoch,
            inverted,
        };
        let id = subframe.id();
        if !(1..=5).contains(&id) {
            return Err(SubframeError::InvalidId { id });
        }
        Ok(subframe)
    }
}

/// Whether `next` is the subframe after `first`: same polarity, time of week one subframe
/// later (the count wraps at the end of the week).
fn follows_in_time(first: &Subframe, next: &Subframe) -> bool {
    let counts_per_week = (WEEK_S / SUBFRAME_S) as u32;
    next.inverted == first.inverted && next.tow_count() == (first.tow_count() + 1) % counts_per_week
}

/// The start epoch of the subframe after the one starting at `start`.
fn next_start(start: u64) -> u64 {
    start.saturating_add(SUBFRAME_BITS * EPOCHS_PER_BIT)
}

#[cfg(test)]
mod tests {
    use heapless::Vec;

    use super::super::parity::{encode_word, solve_trailing_zeros};
    use super::*;

    /// Bits of one subframe.
    const SUBFRAME: usize = 300;
    /// Room for the test stream: a preamble run and four subframes.
    const STREAM: usize = 1280;

    /// Encodes ten data words into 300 transmitted bits after a word ending in `prev`.
    fn encode(words: &[u32; 10], mut prev: (bool, bool)) -> Vec<bool, SUBFRAME> {
        let mut bits = Vec::new();
        for (w, &d) in words.iter().enumerate() {
            let d = if w == 1 || w == 9 {
                solve_trailing_zeros(d, prev.0, prev.1)
            } else {
                d
            };
            let t = encode_word(d, prev.0, prev.1);
            for i in (0..30).rev() {
                bits.push((t >> i) & 1 == 1).expect("300 bits");
            }
            prev = ((t >> 1) & 1 == 1, t & 1 == 1);
        }
        bits
    }

    fn subframe_words(tow_count: u32, id: u32, fill: u32) -> [u32; 10] {
        let mut w = [0u32; 10];
        w[0] = (PREAMBLE << 16) | (0x1234 << 2);
        w[1] = (tow_count << 7) | (id << 2);
        for (k, x) in w.iter_mut().enumerate().skip(2) {
            *x = (fill.wrapping_mul(k as u32 + 7)) & 0xFF_FFFF;
        }
        w
    }

    fn feed(
        sync: &mut SubframeSync,
        bits: &[bool],
        first_epoch: u64,
        invert: bool,
    ) -> Vec<Result<Option<Subframe>, SubframeError>, STREAM> {
        bits.iter()
            .enumerate()
            .map(|(k, &b)| {
                sync.push(&DataBit {
                    value: b ^ invert,
                    start_epoch: first_epoch + 20 * k as u64,
                    strength: 1.0,
                })
            })
            .collect()
    }

    /// Ten bits of lead-in, then subframes with these TOW counts (ids 1, 2, …).
    fn stream_of(tow_counts: &[u32]) -> (Vec<bool, STREAM>, Vec<[u32; 10], 4>) {
        let mut bits: Vec<bool, STREAM> =
            Vec::from_slice(&[true, false, true, true, false, false, true, false]).expect("room");
        bits.extend([false, false]);
        let mut words = Vec::new();
        for (k, &tow) in tow_counts.iter().enumerate() {
            let k = k as u32;
            let w = subframe_words(tow, k % 5 + 1, 0x5A_5A5A ^ k);
            bits.extend(encode(&w, (false, false)));
            words.push(w).expect("at most four subframes");
        }
        (bits, words)
    }

    fn stream() -> (Vec<bool, STREAM>, Vec<[u32; 10], 4>) {
        stream_of(&[1000, 1001, 1002])
    }

    fn decoded(results: &[Result<Option<Subframe>, SubframeError>]) -> Vec<Subframe, 4> {
        results.iter().filter_map(|r| r.ok().flatten()).collect()
    }

    #[test]
    fn subframes_are_found_in_both_polarities() {
        let (bits, words) = stream();
        for invert in [false, true] {
            let mut sync = SubframeSync::new();
            let out: Vec<Subframe, 3> = feed(&mut sync, &bits, 500, invert)
                .into_iter()
                .filter_map(|r| r.unwrap())
                .collect();
            assert_eq!(out.len(), 3, "invert {invert}");
            for (k, s) in out.iter().enumerate() {
                assert_eq!(s.inverted, invert);
                assert_eq!(s.tow_count(), 1000 + k as u32);
                assert_eq!(s.id() as usize, k % 5 + 1);
                assert_eq!(s.start_tow_s(), (999 + k as u32) * 6);
                assert_eq!(s.start_epoch, 500 + 20 * (10 + 300 * k as u64));
                assert_eq!(s.words[2..9], words[k][2..9]);
            }
            assert!(sync.synchronized());
        }
    }

    #[test]
    fn a_window_that_decodes_is_held_until_the_next_subframe_confirms_it() {
        // a lone subframe: it decodes, but nothing follows it in time
        let (bits, _) = stream_of(&[1000]);
        let mut sync = SubframeSync::new();
        assert!(decoded(&feed(&mut sync, &bits, 0, false)).is_empty());
        assert!(!sync.synchronized());
        // a window that decodes followed by one whose time does not follow (a false
        // preamble in the data): dropped; the true pair after it is reported
        let (mut bits, _) = stream_of(&[1000, 1005, 1006]);
        bits.push(true).expect("room"); // the bit after which 1006 is reported
        let mut sync = SubframeSync::new();
        let results = feed(&mut sync, &bits, 0, false);
        let tows: Vec<u32, 4> = decoded(&results).iter().map(|s| s.tow_count()).collect();
        assert_eq!(tows.as_slice(), &[1005, 1006]);
        assert!(
            results.iter().all(|r| r.is_ok()),
            "a candidate is not an error"
        );
        assert!(sync.synchronized());
    }

    #[test]
    fn the_confirming_subframe_is_reported_one_bit_later() {
        let (bits, _) = stream_of(&[1000, 1001]);
        let mut sync = SubframeSync::new();
        let results = feed(&mut sync, &bits[..bits.len() - 1], 0, false);
        assert_eq!(
            decoded(&results).len(),
            0,
            "the pair is complete only at its last bit"
        );
        let last = sync.push(&DataBit {
            value: bits[bits.len() - 1],
            start_epoch: 20 * (bits.len() as u64 - 1),
            strength: 1.0,
        });
        assert_eq!(last.map(|s| s.map(|s| s.tow_count())), Ok(Some(1000)));
        let next = sync.push(&DataBit {
            value: true,
            start_epoch: 20 * bits.len() as u64,
            strength: 1.0,
        });
        assert_eq!(next.map(|s| s.map(|s| s.tow_count())), Ok(Some(1001)));
    }

    #[test]
    fn a_bit_error_in_a_data_word_is_a_parity_error() {
        let (mut bits, _) = stream_of(&[1000, 1001, 1002, 1003]);
        // word 5 of the third subframe (the first two are a confirmed pair)
        let at = 10 + 2 * 300 + 4 * 30 + 7;
        bits[at] = !bits[at];
        let mut sync = SubframeSync::new();
        let results = feed(&mut sync, &bits, 0, false);
        let errors: Vec<_, STREAM> = results.iter().filter_map(|r| r.err()).collect();
        assert_eq!(errors.len(), 1);
        assert!(matches!(errors[0], SubframeError::Parity { word: 5, .. }));
        assert_eq!(
            results.iter().filter(|r| matches!(r, Ok(Some(_)))).count(),
            2
        );
    }

    #[test]
    fn the_week_wraps_in_the_start_time() {
        let s = Subframe {
            words: [0, 0, 0, 0, 0, 0, 0, 0, 0, 0],
            start_epoch: 0,
            inverted: false,
        };
        assert_eq!(s.start_tow_s(), 604_794);
    }
}
