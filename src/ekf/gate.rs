//! Innovation gating by the normalized innovation squared (NIS).

use crate::{real, Real};

/// Probability that a consistent measurement passes a [`NisGate`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GateConfidence {
    /// 95 % of consistent measurements pass.
    P95,
    /// 99 % pass.
    P99,
    /// 99.9 % pass.
    P999,
}

/// χ² quantiles for 1..=12 degrees of freedom (rows) at 95 %, 99 %, 99.9 % (columns).
const CHI2_TABLE: [[f64; 3]; 12] = [
    [3.841_459, 6.634_897, 10.827_566],
    [5.991_465, 9.210_340, 13.815_511],
    [7.814_728, 11.344_867, 16.266_236],
    [9.487_729, 13.276_704, 18.466_827],
    [11.070_498, 15.086_272, 20.515_006],
    [12.591_587, 16.811_894, 22.457_744],
    [14.067_140, 18.475_307, 24.321_886],
    [15.507_313, 20.090_235, 26.124_482],
    [16.918_978, 21.665_994, 27.877_165],
    [18.307_038, 23.209_251, 29.588_298],
    [19.675_138, 24.724_970, 31.264_134],
    [21.026_070, 26.216_967, 32.909_490],
];

/// The χ² quantile for `dof` degrees of freedom: tabulated for `dof ≤ 12`, the Wilson–Hilferty
/// approximation above (relative error below 0.5 % there). Returns `None` for `dof = 0`.
pub fn chi_square_quantile(dof: usize, confidence: GateConfidence) -> Option<f64> {
    let column = match confidence {
        GateConfidence::P95 => 0,
        GateConfidence::P99 => 1,
        GateConfidence::P999 => 2,
    };
    if dof == 0 {
        return None;
    }
    if let Some(row) = CHI2_TABLE.get(dof - 1) {
        return row.get(column).copied();
    }
    // Wilson–Hilferty: χ²_k(p) ≈ k (1 − 2/(9k) + z_p √(2/(9k)))³
    let z = match confidence {
        GateConfidence::P95 => 1.644_853_6,
        GateConfidence::P99 => 2.326_347_9,
        GateConfidence::P999 => 3.090_232_3,
    };
    let k = dof as f64;
    let a = 2.0 / (9.0 * k);
    let c = 1.0 - a + z * libm::sqrt(a);
    Some(k * c * c * c)
}

/// Accepts a measurement when its NIS `yᵀ S⁻¹ y` is at most a threshold.
///
/// A consistent filter's NIS is χ²-distributed with as many degrees of freedom as the
/// measurement has components, so [`NisGate::chi_square`] turns a false-rejection probability
/// into the threshold.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NisGate<T = f32> {
    threshold: T,
}

impl<T: Real> NisGate<T> {
    /// A gate with an explicit NIS threshold (dimensionless). A non-positive or non-finite
    /// threshold gives a gate that rejects everything.
    pub fn new(threshold: T) -> Self {
        Self { threshold }
    }

    /// The gate that passes a consistent `dof`-dimensional measurement with the given
    /// probability. `dof = 0` gives a gate that rejects everything.
    pub fn chi_square(dof: usize, confidence: GateConfidence) -> Self {
        Self::new(real(chi_square_quantile(dof, confidence).unwrap_or(-1.0)))
    }

    /// The NIS threshold.
    pub fn threshold(&self) -> T {
        self.threshold
    }

    /// True when a measurement with this NIS passes.
    pub fn accepts(&self, nis: T) -> bool {
        nis.is_finite() && nis <= self.threshold
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wilson_hilferty_continues_the_table() {
        // The approximation evaluated at dof 12 is close to the tabulated value.
        let z = 2.326_347_9;
        let a = 2.0 / (9.0 * 12.0);
        let wh = 12.0 * (1.0 - a + z * libm::sqrt(a)).powi(3);
        let table = chi_square_quantile(12, GateConfidence::P99).unwrap();
        assert!((wh - table).abs() / table < 5e-3);
        // Quantiles grow with dof and with confidence.
        let q20 = chi_square_quantile(20, GateConfidence::P99).unwrap();
        assert!(q20 > table && (q20 - 37.566).abs() < 0.1);
        assert!(chi_square_quantile(0, GateConfidence::P99).is_none());
    }

    #[test]
    fn gate_rejects_nan_and_large_nis() {
        let g = NisGate::<f32>::chi_square(1, GateConfidence::P99);
        assert!(g.accepts(6.0));
        assert!(!g.accepts(7.0));
        assert!(!g.accepts(f32::NAN));
        assert!(!NisGate::<f32>::chi_square(0, GateConfidence::P95).accepts(0.0));
    }
}
