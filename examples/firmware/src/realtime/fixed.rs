//! Decimal fixed-point printing of the reports' floats with integer formatting only, so that
//! the firmware does not link core's float formatting (`flt2dec`, its Grisu and Dragon tables
//! and code: about 20 KiB of flash that a flight build, printing through `defmt`, would not
//! carry either).

use core::fmt;

/// A value printed with a fixed number of decimals (at most 6), rounded half away from zero;
/// `NaN` and magnitudes beyond 10¹² as `NaN` and `inf`.
#[derive(Clone, Copy)]
pub struct Fixed {
    value: f64,
    decimals: u32,
}

/// `value` with `decimals` digits after the point.
pub fn fixed(value: impl Into<f64>, decimals: u32) -> Fixed {
    Fixed {
        value: value.into(),
        decimals: decimals.min(6),
    }
}

impl fmt::Display for Fixed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.value;
        if v.is_nan() {
            return f.write_str("NaN");
        }
        let sign = if v < 0.0 { "-" } else { "" };
        if !(v.abs() < 1e12) {
            return write!(f, "{sign}inf");
        }
        let scale = 10u64.pow(self.decimals);
        // (below 10¹⁸ < 2⁶⁴: in range; `as` truncates, the added half rounds)
        let m = (v.abs() * scale as f64 + 0.5) as u64;
        let sign = if m == 0 { "" } else { sign };
        if self.decimals == 0 {
            return write!(f, "{sign}{m}");
        }
        write!(
            f,
            "{sign}{}.{:0w$}",
            m / scale,
            m % scale,
            w = self.decimals as usize
        )
    }
}
