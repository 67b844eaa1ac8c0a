//! Frequency refinement after acquisition: the residual Doppler (and, for LEO dynamics, the
//! Doppler rate) from squared prompts (the squaring removes the data bits), see
//! [`super::channel`].
//!
//! # Doppler rate (LEO)
//! With a Doppler rate `ḟ` the squared prompts are a chirp, `Z_k² ∝ e^{j2π·2(δ t_k + ½ ḟ t_k²)}`
//! (`t_k = k T`, carrier NCO held at the acquired Doppler). [`refine_frequency_and_rate`]
//! estimates the pair in four bounded steps:
//! 1. `δ̄`: the frequency search of [`refine_frequency`] over the whole window (the chirp
//!    spreads its peak over `ḟ·W` Hz but leaves its centre at the window's mean frequency);
//! 2. the mean frequencies `δ₁`, `δ₂` of the two halves (searched within
//!    [`HALF_WINDOW_SEARCH_HZ`] of `δ̄`) give `ḟ₀ = (δ₂ − δ₁)/(W/2)`, clamped to the allowed
//!    rate;
//! 3. the squares are de-chirped by `e^{−j2π ḟ₀ (t_k − t_c)²}` (`t_c` the window centre; the
//!    factor 2 of the squaring and the ½ of the phase cancel) and step 2 repeated on them gives
//!    the residual rate;
//! 4. the de-chirped squares' whole-window search (within [`HALF_WINDOW_SEARCH_HZ`] of `δ̄`)
//!    gives the frequency at the window centre.
//!
//! For a window of `W` = 256 ms at 35 dB-Hz the rate comes out to a few Hz/s (the 3rd-order
//! PLL absorbs that), which removes the ±`ḟ W/2` start error (±13 Hz at 100 Hz/s) and the zero
//! initial rate that made the pull-in slow or fail under LEO dynamics.

/// Epochs of the frequency-refinement stage after a hand-over.
pub const REFINEMENT_EPOCHS: usize = 256;

/// Half-range of the refinement's frequency search, Hz.
pub const REFINEMENT_RANGE_HZ: f32 = 250.0;

/// Half-range of the half-window and de-chirped searches around the whole-window estimate, Hz.
pub const HALF_WINDOW_SEARCH_HZ: f32 = 30.0;

/// The residual Doppler `δ` (Hz, within ±[`REFINEMENT_RANGE_HZ`]) from squared prompts
/// `Z_k²` of period `t`: the peak of `|Σ_k Z_k² e^{−j2π(2δ)kt}|` on a 1 Hz grid, refined by a
/// parabola. Bounded: 501 candidates × 256 terms.
pub fn refine_frequency(squares: &[[f32; 2]], t: f32) -> f32 {
    search(squares, t, 0.0, REFINEMENT_RANGE_HZ)
}

/// Residual Doppler and Doppler rate from squared prompts `Z_k²` of period `t`, the rate
/// limited to `±max_rate_hz_s` (see the module documentation). Returns `(δ_c, ḟ)`: the residual
/// Doppler at the window's centre `t_c = (n − 1) t / 2`, Hz, and the rate, Hz/s. With
/// `max_rate_hz_s ≤ 0` (or fewer than 16 squares) it is [`refine_frequency`] with rate 0.
///
/// Bounded: one 501-candidate search over the window, four 61-candidate searches over half
/// windows and one over the window.
pub fn refine_frequency_and_rate(squares: &[[f32; 2]], t: f32, max_rate_hz_s: f32) -> (f32, f32) {
    let mean = refine_frequency(squares, t);
    let n = squares.len();
    if !(max_rate_hz_s > 0.0) || n < 16 || !(t > 0.0) {
        return (mean, 0.0);
    }
    let half = n / 2;
    let (first, second) = squares.split_at(half);
    // Centres of the halves are `half · t` apart.
    let spacing = half as f32 * t;
    let halves = |a: &[[f32; 2]], b: &[[f32; 2]]| -> f32 {
        let d1 = search(a, t, mean, HALF_WINDOW_SEARCH_HZ);
        let d2 = search(b, t, mean, HALF_WINDOW_SEARCH_HZ);
        (d2 - d1) / spacing
    };
    let mut rate = halves(first, second).clamp(-max_rate_hz_s, max_rate_hz_s);
    let mut dechirped = [[0.0f32; 2]; super::refine::REFINEMENT_EPOCHS];
    let m = n.min(dechirped.len());
    dechirp(squares, &mut dechirped[..m], t, rate);
    let (a, b) = dechirped[..m].split_at(m / 2);
    rate = (rate + halves(a, b)).clamp(-max_rate_hz_s, max_rate_hz_s);
    dechirp(squares, &mut dechirped[..m], t, rate);
    let centre = search(&dechirped[..m], t, mean, HALF_WINDOW_SEARCH_HZ);
    if centre.is_finite() && rate.is_finite() {
        (centre, rate)
    } else {
        (mean, 0.0)
    }
}

/// `out_k = Z_k² e^{−j2π ḟ (t_k − t_c)²}`, `t_c` the window centre (the squared prompts'
/// phase is `2 · ½ ḟ t²` cycles: twice the carrier's).
fn dechirp(squares: &[[f32; 2]], out: &mut [[f32; 2]], t: f32, rate: f32) {
    let centre = 0.5 * (out.len().saturating_sub(1)) as f32;
    // (indices from a range, not `enumerate`: its counter keeps an overflow check)
    for (k, (z, o)) in (0..squares.len()).zip(squares.iter().zip(out.iter_mut())) {
        let dt = (k as f32 - centre) * t;
        // Phase in cycles, reduced before the trigonometry (|ḟ dt²| ≤ 150 · 0.0164 cycles).
        let cycles = rate * dt * dt;
        let w = -core::f32::consts::TAU * (cycles - libm::roundf(cycles));
        let (s, c) = (libm::sinf(w), libm::cosf(w));
        *o = [z[0] * c - z[1] * s, z[0] * s + z[1] * c];
    }
}

/// The peak of `|Σ_k Z_k² e^{−j2π(2δ)kt}|` for `δ` on a 1 Hz grid over `centre ± range`,
/// refined by a parabola. Bounded: `2·range + 1` candidates × `squares.len()` terms.
fn search(squares: &[[f32; 2]], t: f32, centre: f32, range: f32) -> f32 {
    let steps = ((2.0 * range) as usize).saturating_add(1);
    let first = libm::roundf(centre) - range;
    let mut best = (0.0f32, 0usize);
    let mut around = [0.0f32; 3];
    let mut previous = [0.0f32; 2];
    for c in 0..steps {
        let delta = first + c as f32;
        let w = -core::f32::consts::TAU * 2.0 * delta * t;
        let (ws, wc) = (libm::sinf(w), libm::cosf(w));
        let (mut rr, mut ri) = (1.0f32, 0.0f32);
        let (mut sr, mut si) = (0.0f32, 0.0f32);
        for z in squares {
            sr += z[0] * rr - z[1] * ri;
            si += z[0] * ri + z[1] * rr;
            let r = rr * wc - ri * ws;
            ri = rr * ws + ri * wc;
            rr = r;
        }
        let m = crate::sqrtf(sr * sr + si * si);
        if m > best.0 {
            best = (m, c);
            around = [previous[1], m, 0.0];
        }
        if best.1.checked_add(1) == Some(c) {
            around[2] = m;
        }
        previous = [previous[1], m];
    }
    let [a, b, c] = around;
    let curvature = 2.0 * b - a - c;
    let offset = if curvature > 0.0 && best.1 > 0 && best.1 < steps - 1 {
        (0.5 * (c - a) / curvature).clamp(-0.5, 0.5)
    } else {
        0.0
    };
    first + best.1 as f32 + offset
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Squared prompts of a carrier with residual `delta` Hz and rate `rate` Hz/s at 1 ms,
    /// SNR per 1 ms prompt `snr`, with deterministic pseudo-random noise and data bits.
    fn squares(delta: f64, rate: f64, snr: f64, seed: u64) -> [[f32; 2]; REFINEMENT_EPOCHS] {
        let mut x = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        let mut uniform = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            ((x >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        let mut out = [[0.0f32; 2]; REFINEMENT_EPOCHS];
        let amp = (2.0 * snr).sqrt(); // noise variance 1 per component
        for (k, o) in out.iter_mut().enumerate() {
            let t = (k as f64 + 0.5) * 1e-3;
            let phase = core::f64::consts::TAU * (delta * t + 0.5 * rate * t * t);
            let bit = if uniform() < 0.5 { 1.0 } else { -1.0 };
            // Box–Muller
            let (u1, u2) = (uniform(), uniform());
            let r = (-2.0 * u1.ln()).sqrt();
            let (n1, n2) = (
                r * (core::f64::consts::TAU * u2).cos(),
                r * (core::f64::consts::TAU * u2).sin(),
            );
            let i = bit * amp * phase.cos() + n1;
            let q = bit * amp * phase.sin() + n2;
            *o = [(i * i - q * q) as f32, (2.0 * i * q) as f32];
        }
        out
    }

    /// At 40 dB-Hz (SNR 10 per 1 ms prompt) the rate comes out within 5 Hz/s over ±100 Hz/s,
    /// and the frequency at the next epoch (the loop's start) within 2 Hz; with the rate
    /// estimate off, the start error (of the order of `ḟ W/2`) exceeds 3 Hz from 60 Hz/s on.
    #[test]
    fn rate_and_frequency_from_chirped_squares() {
        for (k, &(delta, rate)) in [
            (12.0, 0.0),
            (-80.0, 60.0),
            (150.0, -100.0),
            (-30.0, 100.0),
            (40.0, -45.0),
        ]
        .iter()
        .enumerate()
        {
            let z = squares(delta, rate, 10.0, 7 + k as u64);
            let (centre, est) = refine_frequency_and_rate(&z, 1e-3, 150.0);
            let ahead = 0.5 * (REFINEMENT_EPOCHS as f32 + 1.0) * 1e-3;
            let next = centre + est * ahead;
            // True frequency at the middle of epoch 256.
            let truth_next = delta + rate * 256.5e-3;
            assert!((f64::from(est) - rate).abs() < 5.0, "rate {est} vs {rate}");
            assert!(
                (f64::from(next) - truth_next).abs() < 2.0,
                "next {next} vs {truth_next}"
            );
            let (mean, zero) = refine_frequency_and_rate(&z, 1e-3, 0.0);
            assert_eq!(zero, 0.0);
            assert_eq!(mean, refine_frequency(&z, 1e-3));
            if rate.abs() >= 60.0 {
                assert!(
                    (f64::from(mean) - truth_next).abs() > 3.0,
                    "{delta} {rate}: est {est} next {next} truth {truth_next} mean {mean}"
                );
            }
        }
    }
}
