//! Bit planes: each antenna's samples of one block packed into `u32` words, 32 samples a word,
//! once per block and shared by every satellite's correlator.
//!
//! # Word layout
//! Sample `32·w + k` of the block (block-relative index) is bit `k` of word `w` (least
//! significant bit first). A block of `n` samples fills `⌈n/32⌉` words; the bits after the last
//! sample are zero and never read. Per antenna there are up to four planes:
//!
//! | plane | bit = 1 means | present |
//! |---|---|---|
//! | sign I | in-phase sample negative | always |
//! | magnitude I | `|I| = 3` (else 1) | 2-bit |
//! | sign Q | quadrature sample negative | complex |
//! | magnitude Q | `|Q| = 3` (else 1) | 2-bit complex |
//!
//! So a 1-bit sample is `±1` and a 2-bit sample `±1` or `±3`, the values
//! [`SampleFormat::decode`] gives for the packed formats (`00 → +1, 01 → +3, 10 → −1, 11 → −3`).
//!
//! # Packing
//! [`PlaneBuffer::pack_bytes`] reads the front-end byte layouts of [`SampleFormat`] directly
//! (no `i8` copy): `Sign1` by a bit reversal per byte, `Sign1Iq` by the same reversal and a
//! bit unshuffle (I bits even, Q bits odd), `SignMagnitude2` (real and complex) by
//! 256-entry lookup tables that sort each byte's fields into the planes, `MultiChannel2` by
//! multiply-gathers of one channel's bit pair from four bytes at a time, `Cs8`/`Int8` (1-bit
//! only) by the sign bit of each byte. [`PlaneBuffer::pack_i8`] packs decoded `i8` samples
//! with a magnitude threshold (2-bit) or signs only (1-bit). Every packer reproduces
//! `SampleFormat::decode` followed by `pack_i8` (threshold 2) bit for bit; tests check it.

use crate::signal::samples::SampleFormat;
use crate::signal::SampleError;

/// Error returned by the packers of [`PlaneBuffer`], [`AntennaPlanes::new`] and
/// [`BitBlock::new`](super::BitBlock::new).
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum PlaneError {
    /// The byte layout is refused by the sample decoder: bad format parameters, a channel the
    /// stream does not carry, or bytes ending inside a sample.
    #[error("sample bytes refused")]
    Format(#[from] SampleError),
    /// The format cannot fill these planes: `Cs16`, 2-bit planes from a sign-only or 8-bit
    /// format, complex planes from real samples or real planes from complex samples.
    #[error("sample format cannot fill these planes")]
    UnsupportedFormat,
    /// A plane holds fewer words than its sample count needs, or the quadrature samples are
    /// fewer than the in-phase samples.
    #[error("plane shorter than its samples")]
    PlaneLength,
    /// A 2-bit magnitude threshold of 0.
    #[error("magnitude threshold must be at least 1")]
    InvalidThreshold,
    /// The antennas' planes of a block differ in sample count or format, or there are no
    /// antennas.
    #[error("antenna planes of a block differ")]
    BlockMismatch,
}

impl crate::error::Error for PlaneError {
    fn kind(&self) -> crate::error::ErrorKind {
        crate::error::ErrorKind::InvalidInput
    }
}

/// Samples per plane word.
pub const WORD_SAMPLES: usize = 32;

/// Index of the in-phase sign plane.
const SIGN_I: usize = 0;
/// Index of the in-phase magnitude plane.
const MAG_I: usize = 1;
/// Index of the quadrature sign plane.
const SIGN_Q: usize = 2;
/// Index of the quadrature magnitude plane.
const MAG_Q: usize = 3;

/// Quantization of the samples in the planes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Resolution {
    /// Sign only: samples `±1`.
    OneBit,
    /// Sign and magnitude: samples `±1, ±3`.
    TwoBit,
}

/// What the planes of a block hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PlaneFormat {
    /// 1- or 2-bit samples.
    pub resolution: Resolution,
    /// Complex baseband (I and Q planes) or real IF (I planes only).
    pub complex: bool,
}

impl PlaneFormat {
    /// Whether the planes carry magnitude bits.
    pub const fn two_bit(self) -> bool {
        matches!(self.resolution, Resolution::TwoBit)
    }

    /// Planes per antenna (1 to 4; each costs 4 bytes per 32 samples).
    pub const fn planes(self) -> usize {
        (1 + self.two_bit() as usize) * (1 + self.complex as usize)
    }
}

/// The planes of one antenna over one block (borrowed from a [`PlaneBuffer`] or from the
/// caller's own storage).
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AntennaPlanes<'a> {
    /// Sign I, magnitude I, sign Q, magnitude Q; absent planes are empty slices.
    words: [&'a [u32]; 4],
    len: usize,
    format: PlaneFormat,
}

impl<'a> AntennaPlanes<'a> {
    /// Planes over `len` samples from caller storage: `sign_i` always, `mag_i` for 2-bit,
    /// `sign_q` for complex, `mag_q` for 2-bit complex (absent planes: pass empty slices).
    ///
    /// # Errors
    /// [`PlaneError::PlaneLength`] when a plane the format needs has fewer than
    /// `⌈len/32⌉` words.
    pub fn new(
        format: PlaneFormat,
        len: usize,
        sign_i: &'a [u32],
        mag_i: &'a [u32],
        sign_q: &'a [u32],
        mag_q: &'a [u32],
    ) -> Result<Self, PlaneError> {
        let words = len.div_ceil(WORD_SAMPLES);
        let need = |p: &[u32], used: bool| !used || p.len() >= words;
        let two = format.two_bit();
        let ok = need(sign_i, true)
            && need(mag_i, two)
            && need(sign_q, format.complex)
            && need(mag_q, two && format.complex);
        if !ok {
            return Err(PlaneError::PlaneLength);
        }
        Ok(Self {
            words: [sign_i, mag_i, sign_q, mag_q],
            len,
            format,
        })
    }

    /// Samples in the planes.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the planes hold no samples.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// What the planes hold.
    pub fn format(&self) -> PlaneFormat {
        self.format
    }

    /// The in-phase sign plane.
    pub fn sign_i(&self) -> &'a [u32] {
        self.words[SIGN_I]
    }

    /// The in-phase magnitude plane (empty for 1-bit).
    pub fn mag_i(&self) -> &'a [u32] {
        self.words[MAG_I]
    }

    /// The quadrature sign plane (empty for real samples).
    pub fn sign_q(&self) -> &'a [u32] {
        self.words[SIGN_Q]
    }

    /// The quadrature magnitude plane (empty unless 2-bit complex).
    pub fn mag_q(&self) -> &'a [u32] {
        self.words[MAG_Q]
    }

    /// The planes' first `n` samples (all of them for `n ≥ len`).
    pub fn head(&self, n: usize) -> Self {
        let len = n.min(self.len);
        let words = len.div_ceil(WORD_SAMPLES);
        Self {
            words: self.words.map(|w| w.get(..words).unwrap_or(w)),
            len,
            format: self.format,
        }
    }

    /// Unpacks the planes into `i8` samples (`±1`, `±3`, the values
    /// [`SampleFormat::decode`] gives): in-phase into `i`, quadrature into `q` (complex planes
    /// only; `q` is not touched for real ones), from sample `from` on. Returns the samples
    /// written: `min(len − from, i.len())`, and for complex planes at most `q.len()`.
    ///
    /// For the acquisition search, which runs on `i8` samples: a few milliseconds of the
    /// reference antenna, about 2 operations per sample and component.
    pub fn unpack_i8(&self, from: usize, i: &mut [i8], q: &mut [i8]) -> usize {
        let mut n = self.len.saturating_sub(from).min(i.len());
        if self.format.complex {
            n = n.min(q.len());
        }
        let two = self.format.two_bit();
        let len = self.len;
        let unpack = |signs: &[u32], mags: &[u32], out: &mut [i8]| {
            for (k, x) in (from..len).zip(out.iter_mut().take(n)) {
                let (w, b) = (k / WORD_SAMPLES, (k % WORD_SAMPLES) as u32);
                let bit = |p: &[u32]| (p.get(w).copied().unwrap_or(0) >> b) & 1;
                let mag = if two { 1 + 2 * bit(mags) as i8 } else { 1 };
                *x = if bit(signs) == 1 { -mag } else { mag };
            }
        };
        unpack(self.sign_i(), self.mag_i(), i);
        if self.format.complex {
            unpack(self.sign_q(), self.mag_q(), q);
        }
        n
    }

    /// The value (`±1`, `±3`) of sample `k` of component `q` (false: I, true: Q); 0 beyond the
    /// planes. For tests and the scalar reference, not for the hot path.
    pub fn value(&self, k: usize, quadrature: bool) -> i8 {
        let (s, m) = if quadrature {
            (self.sign_q(), self.mag_q())
        } else {
            (self.sign_i(), self.mag_i())
        };
        let bit = |p: &[u32]| (p.get(k / WORD_SAMPLES).copied().unwrap_or(0) >> (k % 32)) & 1;
        if k >= self.len || (quadrature && !self.format.complex) {
            return 0;
        }
        let mag = if self.format.two_bit() {
            1 + 2 * bit(m) as i8
        } else {
            1
        };
        if bit(s) == 1 {
            -mag
        } else {
            mag
        }
    }
}

/// Plane storage of one antenna for up to `32·W` samples (`16·W` bytes), filled by the packers.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PlaneBuffer<const W: usize> {
    planes: [[u32; W]; 4],
    len: usize,
    format: PlaneFormat,
}

impl<const W: usize> PlaneBuffer<W> {
    /// An empty buffer for planes of `format`.
    pub const fn new(format: PlaneFormat) -> Self {
        Self {
            planes: [[0; W]; 4],
            len: 0,
            format,
        }
    }

    /// Capacity, samples.
    pub const fn capacity(&self) -> usize {
        W * WORD_SAMPLES
    }

    /// Samples packed by the last call.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the buffer holds no samples.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// What the planes hold.
    pub fn format(&self) -> PlaneFormat {
        self.format
    }

    /// The packed planes.
    pub fn planes(&self) -> AntennaPlanes<'_> {
        let words = self.len.div_ceil(WORD_SAMPLES).min(W);
        let two = self.format.two_bit();
        let cx = self.format.complex;
        let take = |p: usize, used: bool| {
            if used {
                self.planes[p].get(..words).unwrap_or_default()
            } else {
                &[][..]
            }
        };
        AntennaPlanes {
            words: [
                take(SIGN_I, true),
                take(MAG_I, two),
                take(SIGN_Q, cx),
                take(MAG_Q, two && cx),
            ],
            len: self.len,
            format: self.format,
        }
    }

    /// Packs channel `channel` of the front-end bytes `bytes` (layout `format`, see
    /// [`SampleFormat`]) and returns the number of samples packed: all whole samples of
    /// `bytes`, at most [`capacity`](Self::capacity). Replaces the previous contents.
    ///
    /// 1-bit planes take the sign of any of `Sign1`, `Sign1Iq`, `SignMagnitude2`, `MultiChannel2`, `Cs8`
    /// and `Int8`; 2-bit planes need a format with magnitude bits (`SignMagnitude2`,
    /// `MultiChannel2`; 8-bit samples go through [`pack_i8`](Self::pack_i8) with a threshold).
    ///
    /// # Errors
    /// [`PlaneError::Format`] for bad format parameters, a missing channel or a byte stream
    /// ending inside a sample; [`PlaneError::UnsupportedFormat`] for a format that cannot
    /// fill these planes (`Cs16`, 2-bit from a sign-only or 8-bit format, complex planes from
    /// real samples or the reverse). The buffer is unchanged on error.
    pub fn pack_bytes(
        &mut self,
        format: SampleFormat,
        bytes: &[u8],
        channel: usize,
    ) -> Result<usize, PlaneError> {
        let format = format.validate()?;
        if channel >= format.channels() {
            return Err(SampleError::NoSuchChannel.into());
        }
        if format.is_complex() != self.format.complex {
            return Err(PlaneError::UnsupportedFormat);
        }
        let two = self.format.two_bit();
        let n = format.samples_in(bytes.len()).min(self.capacity());
        // (each packer is a function of its own, `#[inline(never)]`: compiled apart, each loop
        // keeps its registers; inlined into this dispatch they took 3–12 % more instructions
        // on the M4F, e.g. `sm2iq` 22.5 k against 21.1 k per 1 ms of 3 antennas)
        match format {
            SampleFormat::Sign1 if !two => self.pack_sign1(bytes, n),
            SampleFormat::Sign1Iq if !two => self.pack_sign1iq(bytes, n),
            SampleFormat::SignMagnitude2 { complex: false } => self.pack_sm2(bytes, n),
            SampleFormat::SignMagnitude2 { complex: true } => self.pack_sm2iq(bytes, n),
            SampleFormat::MultiChannel2 { .. } => self.pack_mc2(bytes, channel, n),
            SampleFormat::Cs8 if !two => {
                if bytes.len() % 2 != 0 {
                    return Err(SampleError::PartialSample.into());
                }
                self.pack_signs_of_bytes(bytes, n, 2);
            }
            SampleFormat::Int8 if !two => self.pack_signs_of_bytes(bytes, n, 1),
            _ => return Err(PlaneError::UnsupportedFormat),
        }
        self.len = n;
        Ok(n)
    }

    /// Appends the samples of `planes` after the buffer's own (the planes of the same
    /// format from another buffer: the milliseconds an acquisition searches, collected block
    /// by block as the front end delivers them). Returns the number appended: all of them,
    /// or as many as fit (the rest are dropped; the count says so). Bounded by the source's
    /// words.
    ///
    /// # Errors
    /// [`PlaneError::UnsupportedFormat`] when `planes` are of another format; the buffer is
    /// then unchanged.
    pub fn append(&mut self, planes: &AntennaPlanes<'_>) -> Result<usize, PlaneError> {
        if planes.format() != self.format {
            return Err(PlaneError::UnsupportedFormat);
        }
        let n = planes.len().min(self.capacity().saturating_sub(self.len));
        let (w0, shift) = (self.len / WORD_SAMPLES, (self.len % WORD_SAMPLES) as u32);
        let words = n.div_ceil(WORD_SAMPLES);
        for (dst, src) in self.planes.iter_mut().zip(planes.words) {
            // the bits from the first appended one on cleared (a cleared buffer's are stale)
            for (w, d) in dst
                .iter_mut()
                .enumerate()
                .skip(w0)
                .take(words.saturating_add(1))
            {
                *d &= if w == w0 { (1u32 << shift) - 1 } else { 0 };
            }
            for (w, &x) in src.iter().enumerate().take(words) {
                let x = x & tail_mask(n, w);
                if let Some(d) = dst.get_mut(w0.saturating_add(w)) {
                    *d |= x << shift;
                }
                if let (Some(d), true) = (
                    dst.get_mut(w0.saturating_add(w).saturating_add(1)),
                    shift > 0,
                ) {
                    *d |= x >> (WORD_SAMPLES as u32 - shift);
                }
            }
        }
        // (at most the capacity: `n` is bounded by the room left)
        self.len = self.len.saturating_add(n);
        Ok(n)
    }

    /// Empties the buffer (its format kept).
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Packs decoded samples: sign bit `x < 0`, magnitude bit (2-bit) `|x| ≥ threshold`.
    /// `q` is read for complex planes only (it must then be at least as long as `i`). Packs
    /// `min(i.len(), capacity)` samples and returns the count.
    ///
    /// With `threshold = 2` this packs the output of [`SampleFormat::decode`] for the 1- and
    /// 2-bit formats exactly.
    ///
    /// # Errors
    /// [`PlaneError::PlaneLength`] when complex planes are packed and `q` is shorter than
    /// the samples taken from `i`; [`PlaneError::InvalidThreshold`] for a 2-bit threshold of
    /// 0 (every sample would be large).
    pub fn pack_i8(&mut self, i: &[i8], q: &[i8], threshold: u8) -> Result<usize, PlaneError> {
        let n = i.len().min(self.capacity());
        if self.format.complex && q.len() < n {
            return Err(PlaneError::PlaneLength);
        }
        if self.format.two_bit() && threshold == 0 {
            return Err(PlaneError::InvalidThreshold);
        }
        let t = i16::from(threshold);
        let large = |x: i8| u32::from(i16::from(x).abs() >= t);
        let words = n.div_ceil(WORD_SAMPLES);
        for w in 0..words.min(W) {
            let lo = w * WORD_SAMPLES;
            let hi = (lo + WORD_SAMPLES).min(n);
            let (mut si, mut mi, mut sq, mut mq) = (0u32, 0u32, 0u32, 0u32);
            // (bit positions from `0..32`, not `enumerate`: the shifts' bound visible)
            for (k, &x) in (0..WORD_SAMPLES as u32).zip(i.get(lo..hi).unwrap_or_default()) {
                si |= u32::from(x < 0) << k;
                mi |= large(x) << k;
            }
            if self.format.complex {
                for (k, &x) in (0..WORD_SAMPLES as u32).zip(q.get(lo..hi).unwrap_or_default()) {
                    sq |= u32::from(x < 0) << k;
                    mq |= large(x) << k;
                }
            }
            self.set_word(w, [si, mi, sq, mq]);
        }
        self.len = n;
        Ok(n)
    }

    /// Stores word `w` of the four planes (planes the format lacks are stored as 0).
    fn set_word(&mut self, w: usize, mut v: [u32; 4]) {
        if !self.format.two_bit() {
            v[MAG_I] = 0;
            v[MAG_Q] = 0;
        }
        if !self.format.complex {
            v[SIGN_Q] = 0;
            v[MAG_Q] = 0;
        }
        for (p, x) in self.planes.iter_mut().zip(v) {
            if let Some(slot) = p.get_mut(w) {
                *slot = x;
            }
        }
    }

    /// Packs `n` samples from `bytes`, `B` bytes per word, with `word` turning one word's
    /// bytes into the four plane words; the last, partial word from a zero-padded copy.
    #[inline(always)]
    fn pack_words<const B: usize>(
        &mut self,
        bytes: &[u8],
        n: usize,
        word: impl Fn(&[u8; B]) -> [u32; 4],
    ) {
        let words = n.div_ceil(WORD_SAMPLES).min(W);
        let full = (n / WORD_SAMPLES).min(words);
        let mut chunks = bytes.chunks_exact(B);
        for (w, chunk) in (0..full).zip(&mut chunks) {
            if let Ok(b) = <&[u8; B]>::try_from(chunk) {
                self.set_word(w, word(b));
            }
        }
        if full < words {
            let mut last = [0u8; B];
            let from = bytes.get(full.saturating_mul(B)..).unwrap_or_default();
            for (d, &b) in last.iter_mut().zip(from) {
                *d = b;
            }
            let mask = tail_mask(n, full);
            self.set_word(full, word(&last).map(|v| v & mask));
        }
    }

    /// `Sign1`: eight samples a byte, first sample in the most significant bit: the bits of
    /// each byte reversed.
    #[inline(never)]
    fn pack_sign1(&mut self, bytes: &[u8], n: usize) {
        self.pack_words::<4>(bytes, n, |b| [fields_lsb_first(*b), 0, 0, 0]);
    }

    /// `Sign1Iq`: four I/Q pairs a byte, first pair in the two most significant bits: each
    /// byte's bits reversed (pair k in bits 2k, 2k + 1 of a little-endian word), then the
    /// even (I) and odd (Q) bits of each 16 pairs separated by an unshuffle (fewer
    /// instructions than sorting the pairs by the real `SignMagnitude2` table, whose fields
    /// they resemble: 14.9 k against 20.1 k per 1 ms of 3 antennas on the M4F, both inlined
    /// into `pack_bytes`; 12.3 k now).
    #[inline(never)]
    fn pack_sign1iq(&mut self, bytes: &[u8], n: usize) {
        self.pack_words::<8>(bytes, n, |b| {
            let [b0, b1, b2, b3, b4, b5, b6, b7] = *b;
            let first = unshuffle(fields_lsb_first([b0, b1, b2, b3]));
            let second = unshuffle(fields_lsb_first([b4, b5, b6, b7]));
            let si = (first & 0xffff) | (second << 16);
            let sq = (first >> 16) | (second & 0xffff_0000);
            [si, 0, sq, 0]
        });
    }

    /// `SignMagnitude2`, real: four samples a byte (first in bits 7–6); a table sorts each
    /// byte into four sign bits (low nibble) and four magnitude bits (high nibble), two bytes
    /// give a byte of each plane.
    #[inline(never)]
    fn pack_sm2(&mut self, bytes: &[u8], n: usize) {
        self.pack_words::<8>(bytes, n, |b| {
            let (mut s, mut m) = (0u32, 0u32);
            for (k, pair) in b.chunks_exact(2).enumerate() {
                if let &[x, y] = pair {
                    let v = u32::from(SM2_REAL[usize::from(x)])
                        | (u32::from(SM2_REAL[usize::from(y)]) << 8);
                    // v: bits 0–3 and 8–11 signs, 4–7 and 12–15 magnitudes (as nibbles).
                    s |= ((v & 0xf) | ((v >> 4) & 0xf0)) << (8 * k);
                    m |= (((v >> 4) & 0xf) | ((v >> 8) & 0xf0)) << (8 * k);
                }
            }
            [s, m, 0, 0]
        });
    }

    /// `SignMagnitude2`, complex: two samples a byte (first in the high nibble: I sign, I
    /// magnitude, Q sign, Q magnitude); a table spreads each byte's eight bits over the four
    /// planes (two bits each, one plane per byte of the table entry); four bytes make eight
    /// samples of each plane, and four such groups a word.
    #[inline(never)]
    fn pack_sm2iq(&mut self, bytes: &[u8], n: usize) {
        self.pack_words::<16>(bytes, n, |b| {
            let mut acc = [0u32; 4];
            for (a, quad) in acc.iter_mut().zip(b.chunks_exact(4)) {
                if let &[x0, x1, x2, x3] = quad {
                    let t = |x: u8| SM2_COMPLEX[usize::from(x)];
                    *a = t(x0) | (t(x1) << 2) | (t(x2) << 4) | (t(x3) << 6);
                }
            }
            // Byte p of acc[g] is plane p's samples 8g..8g+7: a 4×4 byte transpose.
            let t0 = (acc[0] & 0x00ff_00ff) | ((acc[1] & 0x00ff_00ff) << 8);
            let t1 = ((acc[0] >> 8) & 0x00ff_00ff) | (acc[1] & 0xff00_ff00);
            let t2 = (acc[2] & 0x00ff_00ff) | ((acc[3] & 0x00ff_00ff) << 8);
            let t3 = ((acc[2] >> 8) & 0x00ff_00ff) | (acc[3] & 0xff00_ff00);
            [
                (t0 & 0xffff) | (t2 << 16),
                (t1 & 0xffff) | (t3 << 16),
                (t0 >> 16) | (t2 & 0xffff_0000),
                (t1 >> 16) | (t3 & 0xffff_0000),
            ]
        });
    }

    /// `MultiChannel2`: one byte per sample; channel `c`'s sign and magnitude bits (`2c + 1`,
    /// `2c`) of four bytes gathered by one multiply each.
    #[inline(never)]
    fn pack_mc2(&mut self, bytes: &[u8], channel: usize, n: usize) {
        let channel = channel as u32;
        // Bit 8j (j = 0..3) times 2^(24 − 7j) lands on bit 24 + j; no two partial products
        // share a bit, so there are no carries.
        let gather = |x: u32| ((x & 0x0101_0101).wrapping_mul(0x0102_0408)) >> 24;
        self.pack_words::<32>(bytes, n, |b| {
            let (mut s, mut m) = (0u32, 0u32);
            for (g, quad) in b.chunks_exact(4).enumerate() {
                if let &[x0, x1, x2, x3] = quad {
                    // (the shift's bound visible here: the closure is compiled on its own)
                    let x = u32::from_le_bytes([x0, x1, x2, x3]) >> (2 * (channel & 3));
                    s |= gather(x >> 1) << (4 * g);
                    m |= gather(x) << (4 * g);
                }
            }
            [s, m, 0, 0]
        });
    }

    /// `Cs8` (`stride` 2: I then Q) and `Int8` (`stride` 1): the sign bit of each byte.
    #[inline(never)]
    fn pack_signs_of_bytes(&mut self, bytes: &[u8], n: usize, stride: usize) {
        let gather = |x: u32| (((x >> 7) & 0x0101_0101).wrapping_mul(0x0102_0408)) >> 24;
        if stride == 2 {
            self.pack_words::<64>(bytes, n, |b| {
                let (mut si, mut sq) = (0u32, 0u32);
                for (g, oct) in b.chunks_exact(8).enumerate() {
                    if let &[i0, q0, i1, q1, i2, q2, i3, q3] = oct {
                        si |= gather(u32::from_le_bytes([i0, i1, i2, i3])) << (4 * g);
                        sq |= gather(u32::from_le_bytes([q0, q1, q2, q3])) << (4 * g);
                    }
                }
                [si, 0, sq, 0]
            });
        } else {
            self.pack_words::<32>(bytes, n, |b| {
                let mut si = 0u32;
                for (g, quad) in b.chunks_exact(4).enumerate() {
                    if let &[x0, x1, x2, x3] = quad {
                        si |= gather(u32::from_le_bytes([x0, x1, x2, x3])) << (4 * g);
                    }
                }
                [si, 0, 0, 0]
            });
        }
    }
}

/// Four bytes whose first bit is the most significant as one word whose first bit is bit 0.
#[inline(always)]
fn fields_lsb_first(b: [u8; 4]) -> u32 {
    u32::from_le_bytes(b).reverse_bits().swap_bytes()
}

/// The even bits of `x` gathered into its low half and the odd bits into its high half, each
/// in order (an outer perfect unshuffle: four swap-by-mask steps, written out so that no
/// unroll threshold leaves them a loop).
#[inline(always)]
fn unshuffle(x: u32) -> u32 {
    let x = swap_masked(x, 1, 0x2222_2222);
    let x = swap_masked(x, 2, 0x0c0c_0c0c);
    let x = swap_masked(x, 4, 0x00f0_00f0);
    swap_masked(x, 8, 0x0000_ff00)
}

/// `x` with the bits under `mask` and those `shift` above them exchanged.
#[inline(always)]
fn swap_masked(x: u32, shift: u32, mask: u32) -> u32 {
    let t = (x ^ (x >> shift)) & mask;
    x ^ t ^ (t << shift)
}

/// `SignMagnitude2` real: byte → sign bits of its four samples (bits 0–3, first sample in bit
/// 0) and magnitude bits (bits 4–7).
static SM2_REAL: [u8; 256] = sm2_real_table();

const fn sm2_real_table() -> [u8; 256] {
    let mut t = [0u8; 256];
    let mut b = 0;
    while b < 256 {
        let mut v = 0u8;
        let mut i = 0;
        while i < 4 {
            let field = (b >> (6 - 2 * i)) & 3;
            v |= (((field >> 1) & 1) as u8) << i;
            v |= ((field & 1) as u8) << (4 + i);
            i += 1;
        }
        t[b] = v;
        b += 1;
    }
    t
}

/// `SignMagnitude2` complex: byte → its two samples' bits, two per plane: byte 0 of the entry
/// sign I, byte 1 magnitude I, byte 2 sign Q, byte 3 magnitude Q (first sample in bit 0 of
/// each byte).
static SM2_COMPLEX: [u32; 256] = sm2_complex_table();

const fn sm2_complex_table() -> [u32; 256] {
    let mut t = [0u32; 256];
    let mut b = 0;
    while b < 256 {
        let mut v = 0u32;
        let mut s = 0;
        while s < 2 {
            let nibble = (b >> (4 - 4 * s)) & 0xf;
            v |= (((nibble >> 3) & 1) as u32) << s; // I sign
            v |= (((nibble >> 2) & 1) as u32) << (8 + s); // I magnitude
            v |= (((nibble >> 1) & 1) as u32) << (16 + s); // Q sign
            v |= ((nibble & 1) as u32) << (24 + s); // Q magnitude
            s += 1;
        }
        t[b] = v;
        b += 1;
    }
    t
}

/// The bits of word `w` that hold samples when `n` samples are packed, sample `k` of a
/// word in bit `k`.
pub(crate) fn tail_mask(n: usize, w: usize) -> u32 {
    let valid = n.saturating_sub(w.saturating_mul(WORD_SAMPLES));
    if valid >= WORD_SAMPLES {
        u32::MAX
    } else {
        (1u32 << valid) - 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode_then_pack<const W: usize>(
        fmt: SampleFormat,
        bytes: &[u8],
        channel: usize,
        planes: PlaneFormat,
    ) -> PlaneBuffer<W> {
        let n = fmt.samples_in(bytes.len()).min(32 * W);
        let mut i = [0i8; 512];
        let mut q = [0i8; 512];
        let got = fmt
            .decode(bytes, channel, &mut i[..n], &mut q[..n])
            .unwrap();
        assert_eq!(got, n);
        let mut buf = PlaneBuffer::<W>::new(planes);
        buf.pack_i8(&i[..n], &q[..n], 2).unwrap();
        buf
    }

    fn pseudo_bytes(n: usize, seed: u32) -> [u8; 512] {
        let mut out = [0u8; 512];
        let mut x = seed | 1;
        for b in out.iter_mut().take(n) {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            *b = (x >> 24) as u8;
        }
        out
    }

    /// Blocks of any length appended one after another (into a buffer cleared of stale
    /// bits) hold what one packing of all their samples holds, up to the capacity.
    #[test]
    fn appended_blocks_equal_one_packing_of_their_samples() {
        let format = PlaneFormat {
            resolution: Resolution::TwoBit,
            complex: true,
        };
        let bytes = pseudo_bytes(512, 7);
        let mut i = [0i8; 1024];
        let mut q = [0i8; 1024];
        let fmt = SampleFormat::SignMagnitude2 { complex: true };
        fmt.decode(&bytes, 0, &mut i, &mut q).unwrap();
        for lengths in [
            &[100usize, 37, 32, 1, 200][..],
            &[64, 64, 31, 33],
            &[300, 300, 300],
        ] {
            let mut whole = PlaneBuffer::<12>::new(format);
            let mut appended = PlaneBuffer::<12>::new(format);
            // stale bits everywhere first
            appended.pack_i8(&[-3; 384], &[-3; 384], 2).unwrap();
            appended.clear();
            let mut from = 0;
            for &n in lengths {
                let mut block = PlaneBuffer::<10>::new(format);
                block
                    .pack_i8(&i[from..from + n], &q[from..from + n], 2)
                    .unwrap();
                let room = 384 - appended.len();
                assert_eq!(appended.append(&block.planes()), Ok(n.min(room)));
                from += n;
            }
            whole.pack_i8(&i[..from], &q[..from], 2).unwrap();
            assert_eq!(appended.len(), whole.len());
            let (a, w) = (appended.planes(), whole.planes());
            for k in 0..whole.len() {
                for quadrature in [false, true] {
                    assert_eq!(
                        a.value(k, quadrature),
                        w.value(k, quadrature),
                        "{lengths:?}: {k}"
                    );
                }
            }
            for (pa, pw) in [(a.sign_i(), w.sign_i()), (a.mag_q(), w.mag_q())] {
                assert_eq!(
                    pa, pw,
                    "{lengths:?}: words, the bits after the last sample included"
                );
            }
        }
        let other = PlaneBuffer::<1>::new(PlaneFormat {
            resolution: Resolution::OneBit,
            complex: true,
        });
        let mut buffer = PlaneBuffer::<1>::new(format);
        assert_eq!(
            buffer.append(&other.planes()),
            Err(PlaneError::UnsupportedFormat)
        );
    }

    #[test]
    fn packers_equal_decode_then_pack() {
        let cases = [
            (SampleFormat::Sign1, Resolution::OneBit),
            (SampleFormat::Sign1Iq, Resolution::OneBit),
            (
                SampleFormat::SignMagnitude2 { complex: false },
                Resolution::TwoBit,
            ),
            (
                SampleFormat::SignMagnitude2 { complex: false },
                Resolution::OneBit,
            ),
            (
                SampleFormat::SignMagnitude2 { complex: true },
                Resolution::TwoBit,
            ),
            (
                SampleFormat::SignMagnitude2 { complex: true },
                Resolution::OneBit,
            ),
            (
                SampleFormat::MultiChannel2 { channels: 3 },
                Resolution::TwoBit,
            ),
            (
                SampleFormat::MultiChannel2 { channels: 4 },
                Resolution::OneBit,
            ),
            (SampleFormat::Cs8, Resolution::OneBit),
            (SampleFormat::Int8, Resolution::OneBit),
        ];
        for (k, (fmt, res)) in cases.into_iter().enumerate() {
            for len in [0usize, 1, 7, 31, 32, 33, 100, 255] {
                let bytes = pseudo_bytes(len, 11 + k as u32);
                let bytes = &bytes[..len];
                let pf = PlaneFormat {
                    resolution: res,
                    complex: fmt.is_complex(),
                };
                for ch in 0..fmt.channels() {
                    let mut got = PlaneBuffer::<8>::new(pf);
                    let n = got.pack_bytes(fmt, bytes, ch).unwrap_or(usize::MAX);
                    if fmt == SampleFormat::Cs8 && len % 2 == 1 {
                        assert_eq!(n, usize::MAX);
                        continue;
                    }
                    let want = decode_then_pack::<8>(fmt, bytes, ch, pf);
                    assert_eq!(n, want.len(), "{fmt:?} {len}");
                    let (a, b) = (got.planes(), want.planes());
                    assert_eq!(
                        a.sign_i(),
                        b.sign_i(),
                        "{:?} {:?} len {} ch {}",
                        fmt,
                        res,
                        len,
                        ch
                    );
                    assert_eq!(a.mag_i(), b.mag_i(), "{fmt:?} {res:?} len {len}");
                    assert_eq!(a.sign_q(), b.sign_q(), "{fmt:?} {res:?} len {len}");
                    assert_eq!(a.mag_q(), b.mag_q(), "{fmt:?} {res:?} len {len}");
                    for s in 0..n {
                        let mut i = [0i8; 512];
                        let mut q = [0i8; 512];
                        fmt.decode(bytes, ch, &mut i[..n], &mut q[..n]).unwrap();
                        let one = |x: i8| match res {
                            Resolution::OneBit if x < 0 => -1,
                            Resolution::OneBit => 1,
                            Resolution::TwoBit => x,
                        };
                        assert_eq!(a.value(s, false), one(i[s]));
                        if fmt.is_complex() {
                            assert_eq!(a.value(s, true), one(q[s]));
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn unpacking_gives_the_values_and_heads_keep_the_first_samples() {
        let bytes = pseudo_bytes(200, 5);
        for res in [Resolution::OneBit, Resolution::TwoBit] {
            let fmt = SampleFormat::SignMagnitude2 { complex: true };
            let pf = PlaneFormat {
                resolution: res,
                complex: true,
            };
            let mut buf = PlaneBuffer::<16>::new(pf);
            let n = buf.pack_bytes(fmt, &bytes[..200], 0).unwrap();
            assert_eq!(n, 400);
            let planes = buf.planes();
            for from in [0usize, 1, 31, 32, 77] {
                let (mut i, mut q) = ([0i8; 512], [0i8; 100]);
                // q shorter than the rest: it bounds the samples written
                let got = planes.unpack_i8(from, &mut i, &mut q);
                assert_eq!(got, 100);
                for k in 0..got {
                    assert_eq!(i[k], planes.value(from + k, false), "{res:?} {from} {k}");
                    assert_eq!(q[k], planes.value(from + k, true), "{res:?} {from} {k}");
                }
                assert!(i[got..].iter().all(|&x| x == 0));
            }
            let head = planes.head(45);
            assert_eq!(head.len(), 45);
            assert_eq!(head.sign_i().len(), 2);
            for k in 0..45 {
                assert_eq!(head.value(k, true), planes.value(k, true));
            }
            assert_eq!(head.value(45, false), 0);
            assert_eq!(planes.head(1000).len(), 400);
        }
    }

    #[test]
    fn unsupported_formats_are_refused() {
        let two = PlaneFormat {
            resolution: Resolution::TwoBit,
            complex: false,
        };
        let mut b = PlaneBuffer::<4>::new(two);
        assert_eq!(
            b.pack_bytes(SampleFormat::Sign1, &[0; 8], 0),
            Err(PlaneError::UnsupportedFormat)
        );
        assert_eq!(
            b.pack_bytes(SampleFormat::Cs16 { shift: 3 }, &[0; 8], 0),
            Err(PlaneError::UnsupportedFormat)
        );
        assert_eq!(
            b.pack_bytes(SampleFormat::SignMagnitude2 { complex: true }, &[0; 8], 0),
            Err(PlaneError::UnsupportedFormat)
        );
        let two_complex = PlaneFormat {
            resolution: Resolution::TwoBit,
            complex: true,
        };
        assert_eq!(
            PlaneBuffer::<4>::new(two_complex).pack_bytes(SampleFormat::Sign1Iq, &[0; 8], 0),
            Err(PlaneError::UnsupportedFormat),
            "a sign-only format cannot fill 2-bit planes"
        );
        assert_eq!(
            b.pack_bytes(SampleFormat::MultiChannel2 { channels: 2 }, &[0; 8], 2),
            Err(PlaneError::Format(SampleError::NoSuchChannel))
        );
        assert_eq!(
            b.pack_i8(&[1, 2], &[], 0),
            Err(PlaneError::InvalidThreshold)
        );
        // Capacity bounds the samples packed.
        let n = b.pack_bytes(
            SampleFormat::SignMagnitude2 { complex: false },
            &[0xff; 64],
            0,
        );
        assert_eq!(n, Ok(128));
        assert!(AntennaPlanes::new(two, 33, &[0], &[0, 0], &[], &[]).is_err());
    }
}
