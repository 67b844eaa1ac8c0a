//! Decimal fixed-point printing of the reports' floats with integer arithmetic only, so that
//! the firmware links neither core's float formatting (`flt2dec`, its Grisu and Dragon tables
//! and code: about 20 KiB of flash) nor the rest of `core::fmt` ([`super::say`]).

use super::say::{decimal, Line, Say};

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

impl Say for Fixed {
    #[inline(never)]
    #[optimize(size)]
    fn say(&self, line: &mut Line) {
        let v = self.value;
        if v.is_nan() {
            return line.bytes(b"NaN");
        }
        let sign: &[u8] = if v < 0.0 { b"-" } else { b"" };
        if !(v.abs() < 1e12) {
            line.bytes(sign);
            return line.bytes(b"inf");
        }
        let scale = 10u64.pow(self.decimals);
        // (below 10¹⁸ < 2⁶⁴: in range; `as` truncates, the added half rounds)
        let m = (v.abs() * scale as f64 + 0.5) as u64;
        if m != 0 {
            line.bytes(sign);
        }
        decimal(line, m / scale, 1);
        if self.decimals > 0 {
            line.bytes(b".");
            decimal(line, m % scale, self.decimals as usize);
        }
    }
}
