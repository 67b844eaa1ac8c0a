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
//! Per stream word: `v − ((v ≫ 1) & 0x55…)` (2-bit counts) and one more step to 4-bit counts
//! (at most 4 each), added over three words (at most 12, no overflow), folded into 8-bit
//! counts (at most 24 per fold, ten folds per chunk of [`CHUNK_WORDS`] = 30 words ≤ 240), and
//! summed into the 32-bit total once per chunk.

use super::carrier::CarrierWords;

/// Words per chunk of the kernels (the 8-bit counters' bound: 10 folds of 24).
pub(crate) const CHUNK_WORDS: usize = 30;

/// Largest number of streams per tap (2-bit complex samples, 3-level carrier).
pub(crate) const MAX_STREAMS: usize = 8;

/// The replica of one word: carrier words and the code words of the four taps
/// (early, prompt, late, noise).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct ReplicaWord {
    pub(crate) carrier: CarrierWords,
    pub(crate) taps: [u32; 4],
}

/// The planes of one antenna over a chunk (each as long as the chunk; a plane the format does
/// not have is replaced by the sign plane and ignored).
#[derive(Clone, Copy, Debug)]
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

/// The stream words and their support masks of one word.
#[inline(always)]
fn streams<const CX: bool, const TB: bool, const L3: bool>(
    a: u32,
    ma: u32,
    b: u32,
    mb: u32,
    r: &CarrierWords,
) -> ([u32; MAX_STREAMS], [u32; MAX_STREAMS]) {
    let (c, s, zc, zs) = (r.c, r.s, r.nzc, r.nzs);
    let ta = a ^ ma;
    let tb = b ^ mb;
    let mut u = [0u32; MAX_STREAMS];
    let mut m = [0u32; MAX_STREAMS];
    if CX && !L3 {
        let g = (a ^ b) & r.d;
        let x = b ^ g;
        let y = a ^ g;
        if TB {
            let h = (ta ^ tb) & r.d;
            u[..4].copy_from_slice(&[x ^ c, tb ^ h ^ c, y ^ s, ta ^ h ^ s]);
            m[..4].copy_from_slice(&[zc, zc, zs, zs]);
        } else {
            u[..2].copy_from_slice(&[x ^ c, y ^ s]);
            m[..2].copy_from_slice(&[zc, zs]);
        }
    } else if CX {
        if TB {
            u.copy_from_slice(&[a ^ c, ta ^ c, b ^ s, tb ^ s, b ^ c, tb ^ c, a ^ s, ta ^ s]);
            m.copy_from_slice(&[zc, zc, zs, zs, zc, zc, zs, zs]);
        } else {
            u[..4].copy_from_slice(&[a ^ c, b ^ s, b ^ c, a ^ s]);
            m[..4].copy_from_slice(&[zc, zs, zc, zs]);
        }
    } else if TB {
        u[..4].copy_from_slice(&[a ^ c, ta ^ c, a ^ s, ta ^ s]);
        m[..4].copy_from_slice(&[zc, zc, zs, zs]);
    } else {
        u[..2].copy_from_slice(&[a ^ c, a ^ s]);
        m[..2].copy_from_slice(&[zc, zs]);
    }
    (u, m)
}

/// 4-bit population counts of `v` (each nibble 0–4).
#[inline(always)]
pub(crate) fn nibble_counts(v: u32) -> u32 {
    let pairs = v - ((v >> 1) & 0x5555_5555);
    (pairs & 0x3333_3333) + ((pairs >> 2) & 0x3333_3333)
}

/// 8-bit sums of the nibble counts `n`.
#[inline(always)]
fn byte_counts(n: u32) -> u32 {
    (n & 0x0f0f_0f0f) + ((n >> 4) & 0x0f0f_0f0f)
}

/// The sum of the four 8-bit counts of `b`.
#[inline(always)]
fn byte_total(b: u32) -> u32 {
    let halves = (b & 0x00ff_00ff) + ((b >> 8) & 0x00ff_00ff);
    halves.wrapping_mul(0x0001_0001) >> 16
}

/// Population count of one word (SWAR, the same arithmetic as the kernels).
#[inline(always)]
pub(crate) fn popcount(v: u32) -> u32 {
    byte_total(byte_counts(nibble_counts(v)))
}

/// Adds, for each tap `taps[t]` and stream `j`, the population count of
/// `(stream_j ⊕ tap) [& support_j]` over the chunk's words to `acc[t][j]`. `MASKED` applies
/// the support masks (3-level carrier, or a span edge); without it every bit counts.
/// At most [`CHUNK_WORDS`] words (shorter slices bound the chunk).
#[inline(always)]
pub(crate) fn accumulate<
    const CX: bool,
    const TB: bool,
    const L3: bool,
    const NT: usize,
    const MASKED: bool,
>(
    planes: ChunkPlanes<'_>,
    replica: &[ReplicaWord],
    taps: [usize; NT],
    acc: &mut [[u32; MAX_STREAMS]; 4],
) {
    let j_count = stream_count(CX, TB, L3);
    let mut nib = [[0u32; MAX_STREAMS]; NT];
    let mut bytes = [[0u32; MAX_STREAMS]; NT];
    let mut in_group = 0u32;
    let words = replica
        .iter()
        .take(CHUNK_WORDS)
        .zip(planes.a)
        .zip(planes.ma)
        .zip(planes.b)
        .zip(planes.mb);
    for ((((r, &a), &ma), &b), &mb) in words {
        let (u, m) = streams::<CX, TB, L3>(a, ma, b, mb, &r.carrier);
        for (t, &tap) in taps.iter().enumerate() {
            let code = r.taps[tap & 3];
            for j in 0..j_count {
                let mut v = u[j] ^ code;
                if MASKED {
                    v &= m[j];
                }
                nib[t][j] += nibble_counts(v);
            }
        }
        in_group += 1;
        if in_group == 3 {
            fold(&mut nib, &mut bytes, j_count);
            in_group = 0;
        }
    }
    fold(&mut nib, &mut bytes, j_count);
    for (t, &tap) in taps.iter().enumerate() {
        for j in 0..j_count {
            acc[tap & 3][j] += byte_total(bytes[t][j]);
        }
    }
}

/// Moves the 4-bit counters into the 8-bit counters.
#[inline(always)]
fn fold<const NT: usize>(
    nib: &mut [[u32; MAX_STREAMS]; NT],
    bytes: &mut [[u32; MAX_STREAMS]; NT],
    j_count: usize,
) {
    for (n, b) in nib.iter_mut().zip(bytes.iter_mut()) {
        for j in 0..j_count {
            b[j] += byte_counts(n[j]);
            n[j] = 0;
        }
    }
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
    let j_count = stream_count(complex, two_bit, three);
    let mut sums = [0i32; MAX_STREAMS];
    for (j, s) in sums.iter_mut().enumerate().take(j_count) {
        let n = if stream_uses_s(complex, two_bit, three, j) {
            ns
        } else {
            nc
        };
        // Both at most 2¹⁶ (the largest epoch): exact in i32.
        *s = n as i32 - 2 * p[j] as i32;
    }
    // One product's sum: a 1-bit stream, or 2·sign − t for 2-bit samples.
    let product = |k: usize| {
        if two_bit {
            2 * sums[2 * k] - sums[2 * k + 1]
        } else {
            sums[k]
        }
    };
    if complex && !three {
        let (x, y) = (product(0), product(1));
        (x + y, x - y)
    } else if complex {
        (product(0) + product(1), product(2) - product(3))
    } else {
        (product(0), -product(1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        // The deferred reduction's bounds: 3 words of all ones per nibble, 10 folds per byte.
        let mut bytes = 0u32;
        for _ in 0..10 {
            bytes += byte_counts(3 * nibble_counts(u32::MAX));
        }
        assert_eq!(byte_total(bytes), 960);
    }
}
