//! The LNAV word parity of IS-GPS-200 (20.3.5.2, Table 20-XIV): a (32,26) Hamming code over
//! the 24 data bits of a word and the last two bits `D29*`, `D30*` of the previous word.
//!
//! A transmitted word is 30 bits, `d1 … d24 D25 … D30`, held here in a `u32` with `d1` at bit
//! 29 and `D30` at bit 0. The data bits are sent complemented when the previous word ended
//! in `D30* = 1`: `d_i = D_i ⊕ D30*`. Because every parity equation contains exactly one of
//! `D29*`, `D30*`, a stream received with inverted polarity (the Costas loop's 180°
//! ambiguity) decodes to the same data and passes the same checks, provided `D29*`, `D30*`
//! are taken from the received stream as well; only the preamble must be searched in both
//! polarities ([`super::subframe`]).

/// Source data bits (1-based, `d1` = most significant of 24) in each of `D25 … D30`.
const PARITY_TERMS: [&[u8]; 6] = [
    &[1, 2, 3, 5, 6, 10, 11, 12, 13, 14, 17, 18, 20, 23],
    &[2, 3, 4, 6, 7, 11, 12, 13, 14, 15, 18, 19, 21, 24],
    &[1, 3, 4, 5, 7, 8, 12, 13, 14, 15, 16, 19, 20, 22],
    &[2, 4, 5, 6, 8, 9, 13, 14, 15, 16, 17, 20, 21, 23],
    &[1, 3, 5, 6, 7, 9, 10, 14, 15, 16, 17, 18, 21, 22, 24],
    &[3, 5, 6, 8, 9, 10, 11, 13, 15, 19, 22, 23, 24],
];

/// Which previous-word bit enters each of `D25 … D30`: `true` for `D29*`, `false` for `D30*`.
const USES_D29_STAR: [bool; 6] = [true, false, true, false, false, true];

/// The masks of [`PARITY_TERMS`] over a 24-bit data value (`d1` at bit 23).
const PARITY_MASKS: [u32; 6] = parity_masks();

const fn parity_masks() -> [u32; 6] {
    let mut masks = [0u32; 6];
    let mut k = 0;
    while k < 6 {
        let terms = PARITY_TERMS[k];
        let mut j = 0;
        while j < terms.len() {
            masks[k] |= 1 << (24 - terms[j] as u32);
            j += 1;
        }
        k += 1;
    }
    masks
}

/// Mask of the 24 data bits.
pub const DATA_MASK: u32 = 0x00FF_FFFF;
/// Mask of a 30-bit word.
pub const WORD_MASK: u32 = 0x3FFF_FFFF;

/// Error returned by [`decode_word`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ParityError {
    /// The received `D25 … D30` differ from those computed from the data bits (a bit error
    /// in the word, or the word is not aligned).
    #[error("word parity check failed")]
    Mismatch {
        /// `D25 … D30` computed from the data (`D25` at bit 5).
        computed: u8,
        /// `D25 … D30` received.
        received: u8,
    },
}

impl crate::error::Error for ParityError {
    fn kind(&self) -> crate::error::ErrorKind {
        crate::error::ErrorKind::InvalidInput
    }
}

/// `D25 … D30` (`D25` at bit 5 of the result) of the source data `data` (24 bits, `d1` at bit
/// 23; higher bits ignored) after a word that ended in `d29_star`, `d30_star`.
pub fn parity_bits(data: u32, d29_star: bool, d30_star: bool) -> u8 {
    let mut out = 0u8;
    for (mask, uses_d29) in PARITY_MASKS.iter().zip(USES_D29_STAR) {
        let star = if uses_d29 { d29_star } else { d30_star };
        let bit = ((data & mask).count_ones() & 1 == 1) ^ star;
        out = (out << 1) | u8::from(bit);
    }
    out
}

/// The transmitted 30-bit word of the source data `data` (24 bits) after a word that ended in
/// `d29_star`, `d30_star`: data complemented when `d30_star`, then the parity.
pub fn encode_word(data: u32, d29_star: bool, d30_star: bool) -> u32 {
    let data = data & DATA_MASK;
    let sent = if d30_star { !data & DATA_MASK } else { data };
    (sent << 6) | u32::from(parity_bits(data, d29_star, d30_star))
}

/// The source data (24 bits) of a received 30-bit word `word` after a word that ended in
/// `d29_star`, `d30_star` (as received), checked against its parity.
///
/// # Errors
/// [`ParityError::Mismatch`] when the parity does not match.
pub fn decode_word(word: u32, d29_star: bool, d30_star: bool) -> Result<u32, ParityError> {
    let word = word & WORD_MASK;
    let sent = word >> 6;
    // D_i = d_i ⊕ D30*
    let data = if d30_star { !sent & DATA_MASK } else { sent };
    let computed = parity_bits(data, d29_star, d30_star);
    let received = (word & 0x3F) as u8;
    if computed == received {
        Ok(data)
    } else {
        Err(ParityError::Mismatch { computed, received })
    }
}

/// Source data of a word whose last two bits (`D29`, `D30`) must be zero (the HOW and word
/// 10): bits 23 and 24 of `data` are replaced by the values that make them so
/// (IS-GPS-200 20.3.5.2, "non-information bearing bits used for parity computation").
pub fn solve_trailing_zeros(data: u32, d29_star: bool, d30_star: bool) -> u32 {
    let base = data & DATA_MASK & !0b11;
    let mut best = base;
    for t in 0..4u32 {
        let candidate = base | t;
        if parity_bits(candidate, d29_star, d30_star) & 0b11 == 0 {
            best = candidate;
            break;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    /// RTKLIB's masks over `D29* D30* d1 … d24` at bits 31 … 6 (rcvraw.c, `decode_word`): an
    /// independent statement of Table 20-XIV.
    const RTKLIB_HAMMING: [u32; 6] = [
        0xBB1F_3480,
        0x5D8F_9A40,
        0xAEC7_CD00,
        0x5763_E680,
        0x6BB1_F340,
        0x8B7A_89C0,
    ];

    fn rtklib_parity(data: u32, d29: bool, d30: bool) -> u8 {
        let word = (u32::from(d29) << 31) | (u32::from(d30) << 30) | ((data & DATA_MASK) << 6);
        let mut p = 0u8;
        for m in RTKLIB_HAMMING {
            p = (p << 1) | ((word & m).count_ones() & 1) as u8;
        }
        p
    }

    #[test]
    fn hand_built_words_have_the_tabulated_parity() {
        // d1 alone enters D25, D27 and D29: 101010
        assert_eq!(parity_bits(0x80_0000, false, false), 0b10_1010);
        // d24 alone enters D26, D29 and D30: 010011
        assert_eq!(parity_bits(0x00_0001, false, false), 0b01_0011);
        // no data: D29* sets D25, D27, D30; D30* sets D26, D28, D29
        assert_eq!(parity_bits(0, true, false), 0b10_1001);
        assert_eq!(parity_bits(0, false, true), 0b01_0110);
        // d3 enters all but D28 (D25 D26 D27 D29 D30): 111011
        assert_eq!(parity_bits(0x20_0000, false, false), 0b11_1011);
        // TLM preamble 10001011, rest zero, after a word ending 00 (terms d1 … d8 of each
        // equation): D25 = d1⊕d5 = 0, D26 = d7 = 1, D27 = d1⊕d5⊕d7⊕d8 = 0, D28 = d5⊕d8 = 0,
        // D29 = d1⊕d5⊕d7 = 1, D30 = d5⊕d8 = 0
        let tlm = 0b1000_1011u32 << 16;
        let d = |i: u32| (tlm >> (24 - i)) & 1 == 1;
        let by_hand = [
            d(1) ^ d(2) ^ d(3) ^ d(5) ^ d(6),
            d(2) ^ d(3) ^ d(4) ^ d(6) ^ d(7),
            d(1) ^ d(3) ^ d(4) ^ d(5) ^ d(7) ^ d(8),
            d(2) ^ d(4) ^ d(5) ^ d(6) ^ d(8),
            d(1) ^ d(3) ^ d(5) ^ d(6) ^ d(7),
            d(3) ^ d(5) ^ d(6) ^ d(8),
        ];
        let expected = by_hand.iter().fold(0u8, |acc, &b| (acc << 1) | u8::from(b));
        assert_eq!(parity_bits(tlm, false, false), expected);
        assert_eq!(expected, 0b01_0010);
    }

    #[test]
    fn parity_agrees_with_rtklib_masks_on_many_words() {
        let mut x = 0x1234_5678u32;
        for _ in 0..2000 {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            for (a, b) in [(false, false), (false, true), (true, false), (true, true)] {
                assert_eq!(parity_bits(x, a, b), rtklib_parity(x, a, b));
            }
        }
    }

    #[test]
    fn words_decode_in_both_polarities_and_errors_are_caught() {
        let mut x = 0x0BAD_CAFEu32;
        for _ in 0..500 {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            let data = x & DATA_MASK;
            for (a, b) in [(false, false), (false, true), (true, false), (true, true)] {
                let w = encode_word(data, a, b);
                assert_eq!(decode_word(w, a, b), Ok(data));
                // the whole stream inverted: word and D29*, D30*
                assert_eq!(decode_word(!w & WORD_MASK, !a, !b), Ok(data));
                // any single bit error is detected
                for bit in 0..30 {
                    assert!(decode_word(w ^ (1 << bit), a, b).is_err());
                }
            }
        }
    }

    #[test]
    fn inverted_words_carry_complemented_data_bits() {
        let data = 0x8B_0000;
        let w = encode_word(data, false, true);
        assert_eq!(w >> 6, !data & DATA_MASK);
        assert_eq!(decode_word(w, false, true), Ok(data));
    }

    #[test]
    fn trailing_bits_solve_d29_d30_to_zero() {
        for (a, b) in [(false, false), (false, true), (true, false), (true, true)] {
            for data in [0u32, 0xFF_FFFF, 0x12_3456, 0xAB_CDEF] {
                let solved = solve_trailing_zeros(data, a, b);
                assert_eq!(solved & !0b11, data & DATA_MASK & !0b11);
                assert_eq!(encode_word(solved, a, b) & 0b11, 0);
            }
        }
    }
}
