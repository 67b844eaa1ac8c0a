//! The correlator's sample loop: replica generation (carrier table, code with early/late
//! margins, noise code) and the per-antenna kernels. Integer only; the overflow analysis is in
//! [`super::correlator`].

use super::ca_code::Prn;
#[cfg(target_arch = "arm")]
use super::correlator::CHUNK;
use super::nco::{carrier_index, CODE_WRAP, COS_TABLE, SIN_TABLE};

/// The replica of one chunk (all slices the same length).
pub(crate) struct Replica<'r> {
    pub(crate) cos: &'r [i16],
    pub(crate) sin: &'r [i16],
    pub(crate) early: &'r [i16],
    pub(crate) prompt: &'r [i16],
    pub(crate) late: &'r [i16],
    pub(crate) noise: &'r [i16],
}

/// Fills the carrier replica from `phase` and returns the phase after the last sample.
#[inline]
pub(crate) fn fill_carrier(cos: &mut [i16], sin: &mut [i16], mut phase: u32, step: u32) -> u32 {
    for (c, s) in cos.iter_mut().zip(sin.iter_mut()) {
        let k = carrier_index(phase);
        *c = COS_TABLE[k];
        *s = SIN_TABLE[k];
        phase = phase.wrapping_add(step);
    }
    phase
}

/// Fills `out` with the ±1 code of `prn` from code phase `phase` (2⁻³² chip, `< CODE_WRAP`).
/// The fill is split at the code-period wrap (at most a few per chunk), so the per-sample
/// work is an add, a shift and a table load.
#[inline]
pub(crate) fn fill_code(out: &mut [i16], prn: Prn, phase: u64, step: u64) {
    let table = prn.code_signs();
    let mut phase = phase % CODE_WRAP;
    let mut rest = out;
    // Bounded: each pass fills up to the next wrap, which is at least one sample away when the
    // step is positive; a zero step fills everything in one pass.
    while !rest.is_empty() {
        let to_wrap = if step == 0 {
            rest.len()
        } else {
            ((CODE_WRAP - phase).div_ceil(step) as usize)
                .max(1)
                .min(rest.len())
        };
        let (head, tail) = core::mem::take(&mut rest).split_at_mut(to_wrap);
        let mut ph = phase;
        for r in head.iter_mut() {
            *r = i16::from(table[(ph >> 32) as usize & 1023]);
            // (below CODE_WRAP + one step within a pass, far from 2⁶⁴: never wraps)
            ph = ph.wrapping_add(step);
        }
        phase = ph.checked_sub(CODE_WRAP).unwrap_or(ph) % CODE_WRAP;
        rest = tail;
    }
}

/// Mixed-sample buffers of the Arm path (empty elsewhere).
pub(crate) struct Scratch {
    #[cfg(target_arch = "arm")]
    mi: [i16; CHUNK],
    #[cfg(target_arch = "arm")]
    mq: [i16; CHUNK],
}

impl Scratch {
    pub(crate) fn new() -> Self {
        Self {
            #[cfg(target_arch = "arm")]
            mi: [0; CHUNK],
            #[cfg(target_arch = "arm")]
            mq: [0; CHUNK],
        }
    }
}

/// The four taps of one antenna over one chunk: `[E_I, E_Q, P_I, P_Q, L_I, L_Q, N_I, N_Q]`.
///
/// Two implementations with identical integer results (no overflow, see the module docs):
/// on hosts one fused pass that SIMD units vectorize; on 32-bit Arm (Cortex-M4) a mixing pass
/// into `i16` buffers and two tap passes of four accumulators each, which keeps every operand
/// in the M4's registers (the fused pass needs 8 accumulators and 8 pointers and spills). The
/// firmware self-check compares the Arm path with the host's integers bit for bit.
#[inline]
pub(crate) fn correlate_antenna(
    xi: &[i8],
    xq: Option<&[i8]>,
    r: &Replica<'_>,
    scratch: &mut Scratch,
) -> [i32; 8] {
    #[cfg(target_arch = "arm")]
    {
        let n = xi.len().min(CHUNK);
        let mi = scratch.mi.get_mut(..n).unwrap_or_default();
        let mq = scratch.mq.get_mut(..n).unwrap_or_default();
        match xq {
            Some(q) => mix_complex(xi, q, r.cos, r.sin, mi, mq),
            None => mix_real(xi, r.cos, r.sin, mi, mq),
        }
        let ep = taps_pair(mi, mq, r.early, r.prompt);
        let ln = taps_pair(mi, mq, r.late, r.noise);
        [ep[0], ep[1], ep[2], ep[3], ln[0], ln[1], ln[2], ln[3]]
    }
    #[cfg(not(target_arch = "arm"))]
    {
        let _ = scratch;
        match xq {
            Some(q) => correlate_complex(xi, q, r),
            None => correlate_real(xi, r),
        }
    }
}

/// `Re(x · (c − js))` of a sample `x = i + jq`: fits `i16` (|x| ≤ 128 per component, the
/// carrier ≤ [`CARRIER_AMPLITUDE`](super::nco::CARRIER_AMPLITUDE): at most 2·128·127 = 32 512);
/// the wrapping forms tell the compiler, which cannot see the tables' bound, and never wrap.
/// So for every sum of these kernels: a chunk of [`CHUNK`](super::correlator::CHUNK) products
/// of at most 32 512 fits `i32` by far.
#[inline(always)]
fn mix_i(i: i16, q: i16, c: i16, s: i16) -> i16 {
    i.wrapping_mul(c).wrapping_add(q.wrapping_mul(s))
}

/// `Im(x · (c − js))`, as [`mix_i`].
#[inline(always)]
fn mix_q(i: i16, q: i16, c: i16, s: i16) -> i16 {
    q.wrapping_mul(c).wrapping_sub(i.wrapping_mul(s))
}

/// Prompt only (slaved antennas): `[0, 0, P_I, P_Q, 0, 0, 0, 0]`, one fused pass (few
/// registers on every target).
#[inline]
pub(crate) fn correlate_prompt(xi: &[i8], xq: Option<&[i8]>, r: &Replica<'_>) -> [i32; 8] {
    let (mut pi, mut pq) = (0i32, 0i32);
    match xq {
        Some(xq) => {
            for ((((&i, &q), &c), &s), &p) in xi.iter().zip(xq).zip(r.cos).zip(r.sin).zip(r.prompt)
            {
                let (i, q) = (i16::from(i), i16::from(q));
                pi = pi.wrapping_add(i32::from(mix_i(i, q, c, s)).wrapping_mul(i32::from(p)));
                pq = pq.wrapping_add(i32::from(mix_q(i, q, c, s)).wrapping_mul(i32::from(p)));
            }
        }
        None => {
            for (((&i, &c), &s), &p) in xi.iter().zip(r.cos).zip(r.sin).zip(r.prompt) {
                let i = i16::from(i);
                pi = pi.wrapping_add(i32::from(i.wrapping_mul(c)).wrapping_mul(i32::from(p)));
                pq = pq.wrapping_add(
                    i32::from(i.wrapping_neg().wrapping_mul(s)).wrapping_mul(i32::from(p)),
                );
            }
        }
    }
    [0, 0, pi, pq, 0, 0, 0, 0]
}

/// Fused pass, complex samples: `m = x · (c − js)`, then the four taps.
#[cfg(not(target_arch = "arm"))]
#[inline]
fn correlate_complex(xi: &[i8], xq: &[i8], r: &Replica<'_>) -> [i32; 8] {
    let mut a = [0i32; 8];
    let it = xi
        .iter()
        .zip(xq)
        .zip(r.cos)
        .zip(r.sin)
        .zip(r.early)
        .zip(r.prompt)
        .zip(r.late)
        .zip(r.noise);
    for (((((((&i, &q), &c), &s), &e), &p), &l), &z) in it {
        let (i, q) = (i16::from(i), i16::from(q));
        let (mi, mq) = (i32::from(mix_i(i, q, c, s)), i32::from(mix_q(i, q, c, s)));
        a[0] = a[0].wrapping_add(mi.wrapping_mul(i32::from(e)));
        a[1] = a[1].wrapping_add(mq.wrapping_mul(i32::from(e)));
        a[2] = a[2].wrapping_add(mi.wrapping_mul(i32::from(p)));
        a[3] = a[3].wrapping_add(mq.wrapping_mul(i32::from(p)));
        a[4] = a[4].wrapping_add(mi.wrapping_mul(i32::from(l)));
        a[5] = a[5].wrapping_add(mq.wrapping_mul(i32::from(l)));
        a[6] = a[6].wrapping_add(mi.wrapping_mul(i32::from(z)));
        a[7] = a[7].wrapping_add(mq.wrapping_mul(i32::from(z)));
    }
    a
}

/// Fused pass, real samples.
#[cfg(not(target_arch = "arm"))]
#[inline]
fn correlate_real(xi: &[i8], r: &Replica<'_>) -> [i32; 8] {
    let mut a = [0i32; 8];
    let it = xi
        .iter()
        .zip(r.cos)
        .zip(r.sin)
        .zip(r.early)
        .zip(r.prompt)
        .zip(r.late)
        .zip(r.noise);
    for ((((((&i, &c), &s), &e), &p), &l), &z) in it {
        let i = i16::from(i);
        let (mi, mq) = (
            i32::from(i.wrapping_mul(c)),
            i32::from(i.wrapping_neg().wrapping_mul(s)),
        );
        a[0] = a[0].wrapping_add(mi.wrapping_mul(i32::from(e)));
        a[1] = a[1].wrapping_add(mq.wrapping_mul(i32::from(e)));
        a[2] = a[2].wrapping_add(mi.wrapping_mul(i32::from(p)));
        a[3] = a[3].wrapping_add(mq.wrapping_mul(i32::from(p)));
        a[4] = a[4].wrapping_add(mi.wrapping_mul(i32::from(l)));
        a[5] = a[5].wrapping_add(mq.wrapping_mul(i32::from(l)));
        a[6] = a[6].wrapping_add(mi.wrapping_mul(i32::from(z)));
        a[7] = a[7].wrapping_add(mq.wrapping_mul(i32::from(z)));
    }
    a
}

/// Pass 1, complex samples: `m = x · (c − js)` into `i16` (fits: see the overflow analysis).
#[cfg(target_arch = "arm")]
#[inline]
fn mix_complex(xi: &[i8], xq: &[i8], cos: &[i16], sin: &[i16], mi: &mut [i16], mq: &mut [i16]) {
    let it = xi
        .iter()
        .zip(xq)
        .zip(cos)
        .zip(sin)
        .zip(mi.iter_mut())
        .zip(mq.iter_mut());
    for (((((&i, &q), &c), &s), oi), oq) in it {
        let (i, q) = (i16::from(i), i16::from(q));
        *oi = mix_i(i, q, c, s);
        *oq = mix_q(i, q, c, s);
    }
}

/// Pass 1, real samples: `m = x · (c − js)`.
#[cfg(target_arch = "arm")]
#[inline]
fn mix_real(xi: &[i8], cos: &[i16], sin: &[i16], mi: &mut [i16], mq: &mut [i16]) {
    let it = xi
        .iter()
        .zip(cos)
        .zip(sin)
        .zip(mi.iter_mut())
        .zip(mq.iter_mut());
    for ((((&i, &c), &s), oi), oq) in it {
        let i = i16::from(i);
        *oi = i.wrapping_mul(c);
        *oq = i.wrapping_neg().wrapping_mul(s);
    }
}

/// Pass 2: the I and Q sums of the mixed samples against two code replicas `a`, `b`:
/// `[Σ m_I a, Σ m_Q a, Σ m_I b, Σ m_Q b]`; four accumulators keep every operand in a register
/// (16×16-bit multiply-accumulates, `SMLABB` on the M4).
#[cfg(target_arch = "arm")]
#[inline]
fn taps_pair(mi: &[i16], mq: &[i16], a: &[i16], b: &[i16]) -> [i32; 4] {
    let mut acc = [0i32; 4];
    let w = |x: i16| i32::from(x);
    for (((&xi, &xq), &ca), &cb) in mi.iter().zip(mq).zip(a).zip(b) {
        acc[0] = acc[0].wrapping_add(w(xi).wrapping_mul(w(ca)));
        acc[1] = acc[1].wrapping_add(w(xq).wrapping_mul(w(ca)));
        acc[2] = acc[2].wrapping_add(w(xi).wrapping_mul(w(cb)));
        acc[3] = acc[3].wrapping_add(w(xq).wrapping_mul(w(cb)));
    }
    acc
}
