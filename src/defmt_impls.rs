//! `defmt::Format` for the public types that hold nalgebra matrices (nalgebra has no defmt
//! support, so these cannot be derived). Matrices print as their column-major element slices.

use defmt::{write, Format, Formatter};

use crate::ekf::{Ekf, SequentialUpdateReport, UpdateReport};
use crate::selftest::ConstantVelocityModel;

impl<const N: usize> Format for Ekf<N, f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "Ekf {{ x: {=[?]}, P (column-major): {=[?]} }}",
            self.state().as_slice(),
            self.covariance().as_slice()
        );
    }
}

impl<const M: usize> Format for UpdateReport<M, f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "UpdateReport {{ innovation: {=[?]}, nis: {=f32}, accepted: {=bool} }}",
            self.innovation.as_slice(),
            self.nis,
            self.accepted
        );
    }
}

impl<const M: usize> Format for SequentialUpdateReport<M, f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "SequentialUpdateReport {{ nis: {=[?]}, accepted_mask: {=u32:#b} }}",
            self.nis.as_slice(),
            self.accepted_mask
        );
    }
}

impl Format for ConstantVelocityModel {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "ConstantVelocityModel {{ dt: {=f32}, q_pos: {=f32}, r: {=f32} }}",
            self.f.m13, self.q.m11, self.r.m11
        );
    }
}
