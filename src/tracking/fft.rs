//! A fixed-size in-place complex FFT in f32 (for acquisition), no allocation.
//!
//! `N` is a power of two (checked by [`Fft::new`]); the twiddles are built once (the first
//! quadrant with libm, the rest by symmetry), in the order the stages read them (each stage's
//! `(w, w², w³)` triples side by side, all the stages' triples within `N` entries), so that a
//! butterfly reads one stream of twiddles and none computes a trigonometric function. The
//! transform is a decimation-in-time radix-4 FFT on the bit-reversed input (one radix-2 stage
//! first when `log₂ N` is odd): `⌈log₂ N / 2⌉` stages of `N/4` butterflies of three complex
//! multiplications, against `log₂ N` stages of `N/2` multiplications for radix 2 (on the
//! Cortex-M4F a 1024-point transform costs about half the instructions of the radix-2 one it
//! replaced). Bounded: every loop runs over fixed slices.

/// A complex number as `[re, im]`.
pub type Complex = [f32; 2];

/// The twiddles of an `N`-point FFT, in stage order.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Fft<const N: usize> {
    /// Stage after stage (the radix-4 stages with twiddles, `quarter` = 4, 16, … or 2, 8, …
    /// up to `N/4`), for `k < quarter`: `w^k, w^{2k}, w^{3k}`, `w = e^{−j2π/(4·quarter)}`.
    /// `3 · Σ quarter < N` entries are used; the rest stay zero.
    twiddles: [Complex; N],
}

/// `quarter` of the first radix-4 stage that multiplies by twiddles: the one after the
/// first radix-4 stage (twiddles all 1) for even `log₂ N`, after the radix-2 stage for odd.
const fn first_quarter(n: usize) -> usize {
    if n.trailing_zeros() % 2 == 1 {
        2
    } else {
        4
    }
}

/// `a · b`.
#[inline(always)]
fn mul(a: Complex, b: Complex) -> Complex {
    [a[0] * b[0] - a[1] * b[1], a[0] * b[1] + a[1] * b[0]]
}

impl<const N: usize> Fft<N> {
    /// `None` unless `N` is a power of two ≥ 4.
    pub fn new() -> Option<Self> {
        let mut fft = Self::blank();
        fft.build().then_some(fft)
    }

    /// A transform without its twiddles (all zero: it maps every input to zero until
    /// [`Fft::build`]). `const`, so that the table that holds it is built in place, without a
    /// copy of its `8·N` bytes on the stack.
    pub const fn blank() -> Self {
        Self {
            twiddles: [[0.0; 2]; N],
        }
    }

    /// Builds the twiddles in place; `false` (and nothing built) unless `N` is a power of
    /// two ≥ 4.
    ///
    /// Every twiddle is `e^{−j2πm/N}` for some `m < 3N/4`. The first quadrant's (`m < N/4`,
    /// the last stage's `w^k`) are computed with libm in f64; every other is one of them times
    /// `(−j)^q`, `q = ⌊4m/N⌋`, exactly (a swap and a sign): a quarter of the trigonometric
    /// functions (f64 is software on the Cortex-M4F: 7 M instructions fewer for `N` = 1024).
    pub fn build(&mut self) -> bool {
        if N < 4 || !N.is_power_of_two() {
            return false;
        }
        let quadrant = N / 4;
        let Some(last) = Self::last_stage_offset() else {
            return true;
        };
        let twiddles = &mut self.twiddles;
        // The last stage's w^k = e^{−j2πk/N}, k < N/4: the first quadrant.
        for k in 0..quadrant {
            let a = -2.0 * core::f64::consts::PI * k as f64 / N as f64;
            // (last + 3k < N: the stages' triples fill fewer than N entries)
            if let Some(w) = twiddles.get_mut(last.wrapping_add(k.wrapping_mul(3))) {
                *w = [libm::cos(a) as f32, libm::sin(a) as f32];
            }
        }
        let mut at = 0usize;
        let mut quarter = first_quarter(N);
        // (at most log₄ N stages: quarter grows fourfold up to N; r·k < 3N and the table
        // index stay far below 2³², wrapping forms only keep overflow checks out)
        while quarter < N {
            let len = quarter.saturating_mul(4);
            let scale = N / len.max(1);
            for k in 0..quarter {
                for r in 1..=3usize {
                    let m = r.wrapping_mul(k).wrapping_mul(scale);
                    let first = last.wrapping_add((m % quadrant).wrapping_mul(3));
                    let base = twiddles.get(first).copied().unwrap_or([0.0; 2]);
                    // e^{−j2πm/N} = (−j)^q · e^{−j2π(m mod N/4)/N}; −j·(c + js) = s − jc
                    let w = match (m / quadrant) % 4 {
                        0 => base,
                        1 => [base[1], -base[0]],
                        2 => [-base[0], -base[1]],
                        _ => [-base[1], base[0]],
                    };
                    if let Some(slot) = twiddles.get_mut(at) {
                        *slot = w;
                    }
                    at = at.wrapping_add(1);
                }
            }
            quarter = len;
        }
        true
    }

    /// The offset of the last radix-4 stage with twiddles (`len = N`) in the table (each
    /// stage holds `3 · quarter` entries); `None` without such a stage (`N = 4`).
    fn last_stage_offset() -> Option<usize> {
        let (mut at, mut last) = (0usize, None);
        let mut quarter = first_quarter(N);
        while quarter < N {
            last = Some(at);
            at = at.saturating_add(quarter.saturating_mul(3));
            quarter = quarter.saturating_mul(4);
        }
        last
    }

    /// In-place forward transform `X[k] = Σ x[n] e^{−j2πkn/N}`; `inverse` uses `e^{+j…}`
    /// (unscaled), computed as `conj(FFT(conj(x)))`.
    pub fn transform(&self, x: &mut [Complex; N], inverse: bool) {
        if inverse {
            for v in x.iter_mut() {
                v[1] = -v[1];
            }
        }
        self.forward(x);
        if inverse {
            for v in x.iter_mut() {
                v[1] = -v[1];
            }
        }
    }

    /// In-place forward transform `X[k] = Σ x[n] e^{−j2πkn/N}` (radix 4, see the module
    /// documentation).
    pub fn forward(&self, x: &mut [Complex; N]) {
        bit_reverse(x);
        let mut len = 1;
        if N.trailing_zeros() % 2 == 1 {
            // One radix-2 stage (twiddle 1) to leave an even number of bits.
            for pair in x.chunks_exact_mut(2) {
                if let [a, b] = pair {
                    let (u, v) = (*a, *b);
                    *a = [u[0] + v[0], u[1] + v[1]];
                    *b = [u[0] - v[0], u[1] - v[1]];
                }
            }
            len = 2;
        }
        if len == 1 {
            // The first radix-4 stage: twiddles all 1.
            for quad in x.chunks_exact_mut(4) {
                if let [a, b, c, d] = quad {
                    let (t0, t2, t1, t3) = (*a, *b, *c, *d);
                    let s02 = [t0[0] + t2[0], t0[1] + t2[1]];
                    let d02 = [t0[0] - t2[0], t0[1] - t2[1]];
                    let s13 = [t1[0] + t3[0], t1[1] + t3[1]];
                    let r13 = [t1[1] - t3[1], t3[0] - t1[0]];
                    *a = [s02[0] + s13[0], s02[1] + s13[1]];
                    *b = [d02[0] + r13[0], d02[1] + r13[1]];
                    *c = [s02[0] - s13[0], s02[1] - s13[1]];
                    *d = [d02[0] - r13[0], d02[1] - r13[1]];
                }
            }
            len = 4;
        }
        // (at most log₄ N stages: len grows fourfold up to N)
        let mut at = 0usize;
        while len < N {
            let quarter = len;
            len = len.saturating_mul(4);
            let triples = quarter.saturating_mul(3);
            let twiddles = self
                .twiddles
                .get(at..at.saturating_add(triples))
                .unwrap_or(&[]);
            Self::radix4_stage(x, quarter, twiddles);
            at = at.saturating_add(triples);
        }
    }

    /// One radix-4 stage: every block of `4 · quarter` points holds (bit-reversed) the
    /// transforms of its samples `≡ 0, 2, 1, 3 (mod 4)`, `quarter` points each; they are
    /// combined with the stage's twiddle triples `(w^k, w^{2k}, w^{3k})`,
    /// `w = e^{−j2π/(4·quarter)}`, `k < quarter`.
    fn radix4_stage(x: &mut [Complex; N], quarter: usize, twiddles: &[Complex]) {
        for block in x.chunks_exact_mut(quarter.saturating_mul(4)) {
            let (ab, cd) = block.split_at_mut(quarter.saturating_mul(2));
            let (a, b) = ab.split_at_mut(quarter);
            let (c, d) = cd.split_at_mut(quarter);
            let points = a
                .iter_mut()
                .zip(b.iter_mut())
                .zip(c.iter_mut().zip(d.iter_mut()));
            for (((a, b), (c, d)), w) in points.zip(twiddles.chunks_exact(3)) {
                let &[w1, w2, w3] = w else { continue };
                // residues 0, 2, 1, 3 live in a, b, c, d
                let t0 = *a;
                let t2 = mul(*b, w2);
                let t1 = mul(*c, w1);
                let t3 = mul(*d, w3);
                let s02 = [t0[0] + t2[0], t0[1] + t2[1]];
                let d02 = [t0[0] - t2[0], t0[1] - t2[1]];
                let s13 = [t1[0] + t3[0], t1[1] + t3[1]];
                // −j · (t1 − t3)
                let r13 = [t1[1] - t3[1], t3[0] - t1[0]];
                *a = [s02[0] + s13[0], s02[1] + s13[1]];
                *b = [d02[0] + r13[0], d02[1] + r13[1]];
                *c = [s02[0] - s13[0], s02[1] - s13[1]];
                *d = [d02[0] - r13[0], d02[1] - r13[1]];
            }
        }
    }
}

/// The bit-reversal permutation of `x` (`N` a power of two).
fn bit_reverse<const N: usize>(x: &mut [Complex; N]) {
    let bits = N.trailing_zeros();
    if bits == 0 {
        return;
    }
    for i in 0..N {
        let j = i.reverse_bits() >> (usize::BITS - bits);
        if j > i && j < N {
            x.swap(i, j);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::noise::{SplitMix64, StandardNormal};

    /// The f64 DFT of `x`, directly from its definition.
    fn dft<const N: usize>(x: &[Complex; N], sign: f64) -> [[f64; 2]; N] {
        let mut out = [[0.0f64; 2]; N];
        for (k, o) in out.iter_mut().enumerate() {
            for (n, v) in x.iter().enumerate() {
                let a = sign * 2.0 * core::f64::consts::PI * ((k * n) % N) as f64 / N as f64;
                let (c, s) = (libm::cos(a), libm::sin(a));
                let (re, im) = (f64::from(v[0]), f64::from(v[1]));
                o[0] += re * c - im * s;
                o[1] += re * s + im * c;
            }
        }
        out
    }

    /// The twiddles as the build computed them before it used the quadrant's symmetry:
    /// every one with libm from its own angle.
    fn direct_twiddles<const N: usize>() -> [Complex; N] {
        let mut twiddles = [[0.0f32; 2]; N];
        let (mut at, mut quarter) = (0usize, first_quarter(N));
        while quarter < N {
            let len = quarter * 4;
            for k in 0..quarter {
                for r in 1..=3usize {
                    let a = -2.0 * core::f64::consts::PI * (r * k) as f64 / len as f64;
                    twiddles[at] = [libm::cos(a) as f32, libm::sin(a) as f32];
                    at += 1;
                }
            }
            quarter = len;
        }
        twiddles
    }

    /// The twiddles built from the first quadrant by symmetry against those computed one by
    /// one from their own angles: equal, but on the axes (`m` a multiple of `N/4`), where the
    /// symmetry gives the exact 0 and ±1 and the direct evaluation f64's rounding of them
    /// (`cos(π/2)` = 6·10⁻¹⁷). Returns how many components were such axis values.
    fn symmetric_twiddles_differ_only_on_the_axes<const N: usize>() -> usize {
        let built = Fft::<N>::new().unwrap();
        let direct = direct_twiddles::<N>();
        let mut on_axes = 0;
        for (b, d) in built.twiddles.iter().zip(direct.iter()) {
            for (&x, &y) in b.iter().zip(d) {
                let exact_axis = x == libm::roundf(x) && (x - y).abs() < 1e-15;
                assert!(x == y || exact_axis, "N {N}: {b:?} vs {d:?}");
                on_axes += usize::from(x != y);
            }
        }
        on_axes
    }

    #[test]
    fn the_twiddles_by_symmetry_equal_the_direct_ones_but_exact_on_the_axes() {
        let on_axes = [
            symmetric_twiddles_differ_only_on_the_axes::<4>(),
            symmetric_twiddles_differ_only_on_the_axes::<8>(),
            symmetric_twiddles_differ_only_on_the_axes::<64>(),
            symmetric_twiddles_differ_only_on_the_axes::<512>(),
            symmetric_twiddles_differ_only_on_the_axes::<1024>(),
            symmetric_twiddles_differ_only_on_the_axes::<2048>(),
            symmetric_twiddles_differ_only_on_the_axes::<8192>(),
        ];
        // (the axis angles the stages meet: none for N = 4, more as stages are added)
        assert!(on_axes.iter().all(|&n| n <= 8), "{on_axes:?}");
    }

    /// Largest error of the f32 transform over the largest f64 DFT line.
    fn relative_error<const N: usize>(inverse: bool, seed: u64) -> f64 {
        let mut rng = SplitMix64::new(seed);
        let mut normal = StandardNormal::new();
        let mut x = [[0.0f32; 2]; N];
        for v in x.iter_mut() {
            *v = [normal.sample(&mut rng), normal.sample(&mut rng)];
        }
        let reference = dft(&x, if inverse { 1.0 } else { -1.0 });
        let fft = Fft::<N>::new().unwrap();
        fft.transform(&mut x, inverse);
        let (mut err, mut top) = (0.0f64, 0.0f64);
        for (a, r) in x.iter().zip(reference.iter()) {
            let e = libm::hypot(f64::from(a[0]) - r[0], f64::from(a[1]) - r[1]);
            err = err.max(e);
            top = top.max(libm::hypot(r[0], r[1]));
        }
        err / top
    }

    /// The radix-4 transform (even and odd `log₂ N`, forward and inverse) equals the f64 DFT
    /// to within f32 rounding (a few 10⁻⁷ of the largest line, growing like `log N`).
    #[test]
    fn the_fft_equals_the_f64_dft() {
        for inverse in [false, true] {
            assert!(relative_error::<4>(inverse, 1) < 1e-6);
            assert!(relative_error::<8>(inverse, 2) < 1e-6);
            assert!(relative_error::<64>(inverse, 3) < 2e-6);
            assert!(relative_error::<512>(inverse, 4) < 3e-6);
            assert!(relative_error::<1024>(inverse, 5) < 3e-6);
            assert!(relative_error::<2048>(inverse, 6) < 3e-6);
        }
    }

    /// Sizes that are not powers of two ≥ 4 are refused.
    #[test]
    fn bad_sizes_are_refused() {
        assert!(Fft::<2>::new().is_none());
        assert!(Fft::<12>::new().is_none());
        assert!(Fft::<16>::new().is_some());
    }
}
