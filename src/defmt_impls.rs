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

use crate::attitude::one_stage::{
    AntennaArray, EpochInformation, OneStageFilter, PhaseModel, Prior, SatelliteTerms,
};

impl Format for AntennaArray<f32> {
    fn format(&self, f: Formatter<'_>) {
        let [a, b, c] = self.positions();
        write!(
            f,
            "AntennaArray {{ A: {=[?]}, B: {=[?]}, C: {=[?]} }}",
            a.as_slice(),
            b.as_slice(),
            c.as_slice()
        );
    }
}

impl Format for PhaseModel<f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "PhaseModel {{ k: {=f32} }}", self.wavenumber());
    }
}

impl Format for SatelliteTerms<f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "SatelliteTerms {{ x_squared: {=f32}, gradient: {=[?]}, curvature (column-major): {=[?]} }}",
            self.x_squared,
            self.gradient.as_slice(),
            self.curvature.as_slice()
        );
    }
}

impl Format for EpochInformation<f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "EpochInformation {{ satellites: {=u8}, gradient: {=[?]}, expected diag: {=[?]}, coherent: {=f32}, aligned: {=f32} }}",
            self.satellites,
            self.gradient.as_slice(),
            self.expected.diagonal().as_slice(),
            self.coherent_power,
            self.aligned_power
        );
    }
}

impl Format for Prior<f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "Prior {{ angles: {}, angle covariance (column-major): {=[?]}, rates: {=[?]}, line bias: {=[?]} }}",
            self.angles,
            self.angle_covariance.as_slice(),
            self.rates.as_slice(),
            self.line_bias
        );
    }
}

impl<const N: usize> Format for OneStageFilter<f32, N> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "OneStageFilter {{ angles: {}, rates: {=[?]}, line bias: {=[?]}, status: {} }}",
            self.angles(),
            self.rates().as_slice(),
            self.line_bias(),
            self.lock_status()
        );
    }
}
