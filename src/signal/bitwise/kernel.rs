//! The per-antenna kernels: stream words from the sample planes and the carrier words, XOR
//! with the tap's code word, SWAR population counts with deferred reduction.
//!
//! # Streams
//! A *stream* is one `±1` product per sample whose sum over the integration, with the tap's
//! code, is one term of the output: `Σ_k (−1)^{u_k ⊕ T_k}` over the samples of its support
//! (the span, and `c ≠ 0` or `s ≠ 0` for the 3-level carrier) is `n_support − 2·popcount`.
//! With `x = σ·(1 + 2m)` a sample (sign bit `σ`, magnitude bit `m`), a 2-bit value is
//! `x = 2(−1)^σ − (−1)^{σ⊕m}`, so each 2-bit product is two 1-bit streams (`σ` and
//! `t = σ ⊕ m`) weighted 2 and −1. Per tap:
//!
//! | samples, carrier | streams | output |
//! |---|---|---|
//! | complex, 2-level | `X = C ⊕ (D ? a : b)`, `Y = S ⊕ (D ? b : a)` | `I = X̂ + Ŷ`, `Q = X̂ − Ŷ` |
//! | complex, 3-level | `a⊕C, b⊕S, b⊕C, a⊕S` | `I = A₀ + A₁`, `Q = A₂ − A₃` |
//! | real, either | `a⊕C, a⊕S` | `I = A₀`, `Q = −A₁` |
//!
//! (`a`, `b`: sign planes of I and Q; `D = C ⊕ S`; 2-bit doubles every stream.) The complex
//! 2-level row is the 45° rotation of the mixing: with `c, s = ±1` exactly one of `c − s`,
//! `c + s` is non-zero, so `X = I + Q = 2·(D ? x_I c : x_Q c)` and `Y = I − Q = 2·(D ? x_Q s
//! : x_I c)`, one sample component each: two streams instead of four (`X̂ = X/2`, `Ŷ = Y/2`).
//!
//! # Population counts
//! Stream-major: each stream's words of a chunk are prepared once per antenna
//! ([`prepare`]), then every tap's sum is one loop over two word arrays ([`xor_count`]):
//! `v − ((v ≫ 1) & 0x55…)` (2-bit counts), one more step to 4-bit counts (at most 4 each),
//! added over three words (at most 12, no overflow), folded into 8-bit counts (at most 8 per
//! word, 240 for a chunk of [`CHUNK_WORDS`] = 30 words), summed into the 32-bit total once per
//! chunk. Every operand of the loop fits the Cortex-M4's registers.

use super::carrier::CarrierWords;

/// Words per chunk of the kernels (the 8-bit counters' bound: 30 words of at most 8 each).
pub(crate) const CHUNK_WORDS: usize = 30;

/// Largest number of streams per tap (2-bit complex samples, 3-level carrier).
pub(crate) const MAX_STREAMS: usize = 8;

/// The stream words of one antenna over a chunk, stream-major (scratch reused chunk by chunk).
pub(crate) type StreamWords = [[u32; CHUNK_WORDS]; MAX_STREAMS];

/// The planes of one antenna over a chunk (each as long as the chunk; a plane the format does
/// not have is replaced by the sign plane and ignored).
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub(crate) struct ChunkPlanes<'a> {
    pub(crate) a: &'a [u32],
    pub(crate) ma: &'a [u32],
    pub(crate) b: &'a [u32],
    pub(crate) mb: &'a [u32],
}

/// Streams per tap.
pub(crate) const fn stream_count(complex: bool, two_bit: bool, three: bool) -> usize {
    let base = if complex && three { 4 } else { 2 };
    if two_bit {
        2 * base
    } else {
        base
    }
}

/// Whether stream `j` is counted over the `s ≠ 0` support (else `c ≠ 0`).
pub(crate) const fn stream_uses_s(complex: bool, two_bit: bool, three: bool, j: usize) -> bool {
    let per = if two_bit { 2 } else { 1 };
    let base = j / per;
    if complex && three {
        // a⊕C, b⊕S, b⊕C, a⊕S
        base % 2 == 1
    } else {
        // X (C), Y (S)  /  a⊕C, a⊕S
        base == 1
    }
}

/// The stream words of one word.
#[inline(always)]
fn streams<const CX: bool, const TB: bool, const L3: bool>(
    a: u32,
    ma: u32,
    b: u32,
    mb: u32,
    r: &CarrierWords,
) -> [u32; MAX_STREAMS] {
    let (c, s) = (r.c, r.s);
    let ta = a ^ ma;
    let tb = b ^ mb;
    if CX && !L3 {
        let g = (a ^ b) & r.d;
        let (x, y) = (b ^ g, a ^ g);
        if TB {
            let h = (ta ^ tb) & r.d;
            [x ^ c, tb ^ h ^ c, y ^ s, ta ^ h ^ s, 0, 0, 0, 0]
        } else {
            [x ^ c, y ^ s, 0, 0, 0, 0, 0, 0]
        }
    } else if CX {
        if TB {
            [a ^ c, ta ^ c, b ^ s, tb ^ s, b ^ c, tb ^ c, a ^ s, ta ^ s]
        } else {
            [a ^ c, b ^ s, b ^ c, a ^ s, 0, 0, 0, 0]
        }
    } else if TB {
        [a ^ c, ta ^ c, a ^ s, ta ^ s, 0, 0, 0, 0]
    } else {
        [a ^ c, a ^ s, 0, 0, 0, 0, 0, 0]
    }
}

/// Fills `out` with the stream words of the chunk's words (`carrier.len()` of them, at most
/// [`CHUNK_WORDS`]), each masked (AND) with its support mask for the 3-level carrier; the
/// 2-level carrier's masks are all ones except at a span's edges, which the caller applies to
/// the first and last word only. Only the format's [`stream_count`] streams are written.
#[inline(always)]
pub(crate) fn prepare<const CX: bool, const TB: bool, const L3: bool>(
    planes: ChunkPlanes<'_>,
    carrier: &[CarrierWords],
    out: &mut StreamWords,
) {
    let [o0, o1, o2, o3, o4, o5, o6, o7] = out;
    // (one loop per stream count: a loop writes only the streams it has, so each keeps its
    // few output pointers in registers)
    match stream_count(CX, TB, L3) {
        2 => prepare_n::<CX, TB, L3, 2>(planes, carrier, [o0, o1]),
        4 => prepare_n::<CX, TB, L3, 4>(planes, carrier, [o0, o1, o2, o3]),
        _ => prepare_n::<CX, TB, L3, 8>(planes, carrier, [o0, o1, o2, o3, o4, o5, o6, o7]),
    }
}

/// [`prepare`] for `J` streams.
#[inline(always)]
fn prepare_n<const CX: bool, const TB: bool, const L3: bool, const J: usize>(
    planes: ChunkPlanes<'_>,
    carrier: &[CarrierWords],
    mut outs: [&mut [u32; CHUNK_WORDS]; J],
) {
    let inputs = carrier
        .iter()
        .zip(planes.a)
        .zip(planes.ma)
        .zip(planes.b)
        .zip(planes.mb);
    for (w, inputs) in (0..CHUNK_WORDS).zip(inputs) {
        let ((((r, &a), &ma), &b), &mb) = inputs;
        let u = streams::<CX, TB, L3>(a, ma, b, mb, r);
        for (j, (out, x)) in (0..J).zip(outs.iter_mut().zip(u)) {
            let mask = if !L3 {
                u32::MAX
            } else if stream_uses_s(CX, TB, L3, j) {
                r.nzs
            } else {
                r.nzc
            };
            // (w < CHUNK_WORDS: always present)
            if let Some(slot) = out.get_mut(w) {
                *slot = x & mask;
            }
        }
    }
}

/// 4-bit population counts of `v` (each nibble 0–4).
#[inline(always)]
pub(crate) fn nibble_counts(v: u32) -> u32 {
    // (SWAR: every field's sum stays within its field, so the word never wraps; the
    // wrapping forms tell the compiler, which cannot see the fields)
    let pairs = v.wrapping_sub((v >> 1) & 0x5555_5555);
    (pairs & 0x3333_3333).wrapping_add((pairs >> 2) & 0x3333_3333)
}

/// 8-bit sums of the nibble counts `n`.
#[inline(always)]
fn byte_counts(n: u32) -> u32 {
    (n & 0x0f0f_0f0f).wrapping_add((n >> 4) & 0x0f0f_0f0f)
}

/// The sum of the four 8-bit counts of `b`.
#[inline(always)]
fn byte_total(b: u32) -> u32 {
    let halves = (b & 0x00ff_00ff).wrapping_add((b >> 8) & 0x00ff_00ff);
    halves.wrapping_mul(0x0001_0001) >> 16
}

/// Population count of one word (SWAR, the same arithmetic as the kernels).
#[inline(always)]
pub(crate) fn popcount(v: u32) -> u32 {
    byte_total(byte_counts(nibble_counts(v)))
}

/// `Σ popcount(x_w ⊕ t_w)` over the common words of `x` and `t`, at most [`CHUNK_WORDS`],
/// folded into 8-bit counts (at most 8 per word, 240 for 30 words) and summed once at the end.
/// On the Cortex-M ([`xor_count_swar`]) 4-bit counts are first summed over three words, which
/// saves a fold per word in its registers; elsewhere every word is folded to 8-bit counts on
/// its own and the words are summed lane by lane, a loop without a carried dependency that the
/// compiler vectorizes with the baseline SIMD (SSE2 on x86-64: about twice the speed of a
/// full population count per word, without `-C target-cpu`).
#[inline(always)]
pub(crate) fn xor_count(x: &[u32], t: &[u32]) -> u32 {
    #[cfg(not(target_arch = "arm"))]
    {
        let bytes = x.iter().zip(t).take(CHUNK_WORDS).fold(0u32, |acc, (a, b)| {
            acc.wrapping_add(byte_counts(nibble_counts(a ^ b)))
        });
        byte_total(bytes)
    }
    #[cfg(target_arch = "arm")]
    {
        xor_count_swar(x, t)
    }
}

/// The Cortex-M path of [`xor_count`] (and the reference for the host path in tests).
#[cfg_attr(not(target_arch = "arm"), allow(dead_code))]
#[inline(always)]
pub(crate) fn xor_count_swar(x: &[u32], t: &[u32]) -> u32 {
    let n = x.len().min(t.len()).min(CHUNK_WORDS);
    let (x, t) = (
        x.get(..n).unwrap_or_default(),
        t.get(..n).unwrap_or_default(),
    );
    let mut bytes = 0u32;
    let mut xs = x.chunks_exact(3);
    let mut ts = t.chunks_exact(3);
    for (a, b) in (&mut xs).zip(&mut ts) {
        if let (&[a0, a1, a2], &[b0, b1, b2]) = (a, b) {
            // (field sums within their fields, as documented above: no word wraps)
            let nib = nibble_counts(a0 ^ b0)
                .wrapping_add(nibble_counts(a1 ^ b1))
                .wrapping_add(nibble_counts(a2 ^ b2));
            bytes = bytes.wrapping_add(byte_counts(nib));
        }
    }
    let mut nib = 0u32;
    for (&a, &b) in xs.remainder().iter().zip(ts.remainder()) {
        nib = nib.wrapping_add(nibble_counts(a ^ b));
    }
    byte_total(bytes.wrapping_add(byte_counts(nib)))
}

/// `(I, Q)` of one tap from its streams' population counts `p` and the support counts `nc`
/// (samples with `c ≠ 0`) and `ns` (`s ≠ 0`); both are the span's sample count for the
/// 2-level carrier. See the module documentation for the combinations.
pub(crate) fn combine(
    complex: bool,
    two_bit: bool,
    three: bool,
    p: &[u32; MAX_STREAMS],
    nc: u32,
    ns: u32,
) -> (i32, i32) {
    // (in i64, exact for any u32 counts; the counts are at most 2¹⁶, the largest epoch, so
    // the results fit i32 and the final saturation never acts. Each stream's sum is taken
    // where it is used: no array of sums to clear and fill, once per tap and epoch.)
    let sum = |j: usize| {
        let n = if stream_uses_s(complex, two_bit, three, j) {
            ns
        } else {
            nc
        };
        // (j < MAX_STREAMS: always present)
        i64::from(n) - 2 * i64::from(p.get(j).copied().unwrap_or(0))
    };
    // One product's sum: a 1-bit stream, or 2·sign − t for 2-bit samples.
    let product = |k: usize| {
        if two_bit {
            2 * sum(2 * k) - sum(2 * k + 1)
        } else {
            sum(k)
        }
    };
    let narrow = |v: i64| v.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32;
    let (i, q) = if complex && !three {
        let (x, y) = (product(0), product(1));
        (x + y, x - y)
    } else if complex {
        (product(0) + product(1), product(2) - product(3))
    } else {
        (product(0), -product(1))
    };
    (narrow(i), narrow(q))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xor_count_is_exact_for_every_length() {
        let mut x = [0u32; CHUNK_WORDS];
        let mut t = [0u32; CHUNK_WORDS];
        let mut r = 0x1234_5677u32;
        for (a, b) in x.iter_mut().zip(t.iter_mut()) {
            r ^= r << 13;
            r ^= r >> 17;
            r ^= r << 5;
            *a = r;
            *b = r.rotate_left(7) ^ 0x0f0f_f0f0;
        }
        for n in 0..=CHUNK_WORDS {
            let want: u32 = x[..n]
                .iter()
                .zip(&t[..n])
                .map(|(a, b)| (a ^ b).count_ones())
                .sum();
            assert_eq!(xor_count(&x[..n], &t[..n]), want);
            assert_eq!(xor_count_swar(&x[..n], &t[..n]), want);
        }
        let ones = [u32::MAX; CHUNK_WORDS];
        assert_eq!(xor_count(&ones, &[0; CHUNK_WORDS]), 960);
    }

    #[test]
    fn swar_popcount_is_exact() {
        let mut x = 0x9e37_79b9u32;
        for _ in 0..10_000 {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            assert_eq!(popcount(x), x.count_ones());
        }
        assert_eq!(popcount(u32::MAX), 32);
        assert_eq!(popcount(0), 0);
    }
}
