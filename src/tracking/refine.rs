//! Frequency refinement after acquisition: the residual Doppler from squared prompts (the
//! squaring removes the data bits), see [`super::channel`].

/// Epochs of the frequency-refinement stage after a hand-over.
pub const REFINEMENT_EPOCHS: usize = 256;

/// Half-range of the refinement's frequency search, Hz.
pub const REFINEMENT_RANGE_HZ: f32 = 250.0;

/// The residual Doppler `δ` (Hz, within ±[`REFINEMENT_RANGE_HZ`]) from squared prompts
/// `Z_k²` of period `t`: the peak of `|Σ_k Z_k² e^{−j2π(2δ)kt}|` on a 1 Hz grid, refined by a
/// parabola. Bounded: 501 candidates × 256 terms.
pub fn refine_frequency(squares: &[[f32; 2]], t: f32) -> f32 {
    let steps = (2.0 * REFINEMENT_RANGE_HZ) as usize + 1;
    let mut best = (0.0f32, 0usize);
    let mut around = [0.0f32; 3];
    let mut previous = [0.0f32; 2];
    for c in 0..steps {
        let delta = c as f32 - REFINEMENT_RANGE_HZ;
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
        let m = libm::sqrtf(sr * sr + si * si);
        if m > best.0 {
            best = (m, c);
            around = [previous[1], m, 0.0];
        }
        if c == best.1 + 1 {
            around[2] = m;
        }
        previous = [previous[1], m];
    }
    let [a, b, c] = around;
    let curvature = 2.0 * b - a - c;
    let offset = if curvature > 0.0 && best.1 > 0 && best.1 + 1 < steps {
        (0.5 * (c - a) / curvature).clamp(-0.5, 0.5)
    } else {
        0.0
    };
    best.1 as f32 - REFINEMENT_RANGE_HZ + offset
}
