//! Small statistics helpers shared by the scenarios.

use std::f64::consts::{PI, TAU};

/// Root mean square; 0 for an empty slice.
pub fn rms(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    (values.iter().map(|v| v * v).sum::<f64>() / values.len() as f64).sqrt()
}

/// Arithmetic mean; 0 for an empty slice.
pub fn mean(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.iter().sum::<f64>() / values.len() as f64
}

/// Sample standard deviation (n − 1); 0 for fewer than two values.
pub fn std_dev(values: &[f64]) -> f64 {
    if values.len() < 2 {
        return 0.0;
    }
    let m = mean(values);
    (values.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (values.len() - 1) as f64).sqrt()
}

/// Largest absolute value; 0 for an empty slice.
pub fn max_abs(values: &[f64]) -> f64 {
    values.iter().fold(0.0, |m, v| m.max(v.abs()))
}

/// The `p`-quantile (0 ≤ p ≤ 1) by linear interpolation between order statistics.
pub fn quantile(values: &[f64], p: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let mut v: Vec<f64> = values.to_vec();
    v.sort_by(f64::total_cmp);
    let pos = p.clamp(0.0, 1.0) * (v.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = pos.ceil() as usize;
    let frac = pos - lo as f64;
    v[lo] * (1.0 - frac) + v[hi] * frac
}

/// Two-sided `1 − alpha` interval for the mean of `runs` independent χ²(`dof`) variables
/// divided by `runs`, i.e. for an average NEES (Bar-Shalom's consistency test), by the
/// Wilson–Hilferty approximation of the χ²(`runs·dof`) quantiles.
pub fn average_chi_square_interval(dof: usize, runs: usize, alpha: f64) -> (f64, f64) {
    let k = (dof * runs) as f64;
    let z = normal_quantile(1.0 - alpha / 2.0);
    let a = 2.0 / (9.0 * k);
    let q = |zz: f64| k * (1.0 - a + zz * a.sqrt()).powi(3);
    (q(-z) / runs as f64, q(z) / runs as f64)
}

/// Quantile of the standard normal distribution (Acklam's rational approximation, relative
/// error below 1.2e-9).
pub fn normal_quantile(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969683028665376e1,
        2.209460984245205e2,
        -2.759285104469687e2,
        1.38357751867269e2,
        -3.066479806614716e1,
        2.506628277459239,
    ];
    const B: [f64; 5] = [
        -5.447609879822406e1,
        1.615858368580409e2,
        -1.556989798598866e2,
        6.680131188771972e1,
        -1.328068155288572e1,
    ];
    const C: [f64; 6] = [
        -7.784894002430293e-3,
        -3.223964580411365e-1,
        -2.400758277161838,
        -2.549732539343734,
        4.374664141464968,
        2.938163982698783,
    ];
    const D: [f64; 4] = [
        7.784695709041462e-3,
        3.224671290700398e-1,
        2.445134137142996,
        3.754408661907416,
    ];
    let p = p.clamp(1e-300, 1.0 - 1e-16);
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    if p < 0.02425 {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - 0.02425 {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    }
}

/// Density of the phase error of a phasor in complex Gaussian noise at SNR `rho` (`A²/2σ²`).
fn phase_density(theta: f64, rho: f64) -> f64 {
    let c = theta.cos();
    (-rho).exp() / TAU
        + (rho.sqrt() * c / (2.0 * PI.sqrt()))
            * (-rho * theta.sin().powi(2)).exp()
            * (1.0 + libm::erf(rho.sqrt() * c))
}

/// RMS (cycles) of the wrapped difference of the phases of two independent prompts at
/// `(C/N0)·T`: numerical circular convolution of the phase density of a noisy phasor on a 720-point grid.
pub fn phase_difference_rms_cycles(cn0_dbhz: f64, t: f64) -> f64 {
    let rho = 10f64.powf(cn0_dbhz / 10.0) * t;
    const M: usize = 720;
    let h = TAU / M as f64;
    let p: Vec<f64> = (0..M)
        .map(|k| phase_density(-PI + (k as f64 + 0.5) * h, rho) * h)
        .collect();
    let norm: f64 = p.iter().sum();
    let mut second = 0.0;
    for (j, pj) in p.iter().enumerate() {
        for (k, pk) in p.iter().enumerate() {
            let d = ((j as f64 - k as f64) * h + PI).rem_euclid(TAU) - PI;
            second += pj * pk * d * d;
        }
    }
    (second / (norm * norm)).sqrt() / TAU
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn basic_statistics() {
        let v = [1.0, -2.0, 3.0, -4.0];
        assert!((rms(&v) - (30.0f64 / 4.0).sqrt()).abs() < 1e-15);
        assert_eq!(max_abs(&v), 4.0);
        assert_eq!(quantile(&v, 0.5), -0.5);
        assert!((normal_quantile(0.975) - 1.959963985).abs() < 1e-8);
        assert!((normal_quantile(0.001) + 3.090232306).abs() < 1e-8);
    }

    #[test]
    fn average_chi_square_interval_brackets_the_dof() {
        // 50 runs of a 6-dof NEES: χ²₃₀₀ quantiles / 50 = [5.078, 6.997] (scipy).
        let (lo, hi) = average_chi_square_interval(6, 50, 0.05);
        assert!(lo < 6.0 && hi > 6.0);
        assert!(
            (lo - 5.08).abs() < 0.05 && (hi - 6.98).abs() < 0.05,
            "{lo} {hi}"
        );
    }
}
