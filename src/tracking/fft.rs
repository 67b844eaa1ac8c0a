//! A fixed-size in-place radix-2 complex FFT in f32 (for acquisition), no allocation.
//!
//! `N` is a power of two (checked by [`Fft::new`]); the twiddle table `e^{−j2πk/N}` is built
//! once with libm. Bounded: `log₂ N` stages of `N/2` butterflies.

/// A complex number as `[re, im]`.
pub type Complex = [f32; 2];

/// Twiddles and the bit-reversal permutation of an `N`-point FFT.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Fft<const N: usize> {
    twiddles: [Complex; N],
}

impl<const N: usize> Fft<N> {
    /// `None` unless `N` is a power of two ≥ 4.
    pub fn new() -> Option<Self> {
        if N < 4 || !N.is_power_of_two() {
            return None;
        }
        let mut twiddles = [[0.0; 2]; N];
        for (k, w) in twiddles.iter_mut().enumerate() {
            let a = -2.0 * core::f64::consts::PI * k as f64 / N as f64;
            *w = [libm::cos(a) as f32, libm::sin(a) as f32];
        }
        Some(Self { twiddles })
    }

    /// In-place forward transform `X[k] = Σ x[n] e^{−j2πkn/N}`; `inverse` uses `e^{+j…}`
    /// (unscaled), computed as `conj(FFT(conj(x)))`.
    pub fn transform(&self, x: &mut [Complex; N], inverse: bool) {
        if inverse {
            for v in x.iter_mut() {
                v[1] = -v[1];
            }
        }
        // Bit-reversal permutation.
        let bits = N.trailing_zeros();
        for i in 0..N {
            let j = i.reverse_bits() >> (usize::BITS - bits);
            if j > i && j < N {
                x.swap(i, j);
            }
        }
        let mut len = 2;
        while len <= N {
            let half = len / 2;
            let stride = N / len;
            for block in x.chunks_exact_mut(len) {
                let (lo, hi) = block.split_at_mut(half);
                for ((u, v), w) in lo
                    .iter_mut()
                    .zip(hi.iter_mut())
                    .zip(self.twiddles.iter().step_by(stride))
                {
                    let t = [v[0] * w[0] - v[1] * w[1], v[0] * w[1] + v[1] * w[0]];
                    let a = *u;
                    *u = [a[0] + t[0], a[1] + t[1]];
                    *v = [a[0] - t[0], a[1] - t[1]];
                }
            }
            len *= 2;
        }
        if inverse {
            for v in x.iter_mut() {
                v[1] = -v[1];
            }
        }
    }
}
