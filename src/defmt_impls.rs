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

use crate::attitude::baseline_epoch::{AntennaArray, BaselineEpoch};
use crate::attitude::dcm_filter::DirectionCosineFilter;
use crate::attitude::direction_cosine::DirectionCosineModel;
use crate::attitude::filter_estimate::FilterEstimate;
use crate::attitude::multi_structure::{MultiStructureEstimate, MultiStructureFilter};
use crate::attitude::rigid_body::RigidBodyFilter;

impl Format for AntennaArray<f32> {
    fn format(&self, f: Formatter<'_>) {
        let [r1, r2, r3] = self.positions();
        write!(
            f,
            "AntennaArray {{ r1: {=[?]}, r2: {=[?]}, r3: {=[?]} }}",
            r1.as_slice(),
            r2.as_slice(),
            r3.as_slice()
        );
    }
}

impl Format for BaselineEpoch<f32> {
    fn format(&self, f: Formatter<'_>) {
        let present = |v: &[Option<nalgebra::Vector3<f32>>; 3]| v.map(|x| x.is_some());
        write!(
            f,
            "BaselineEpoch {{ baselines present: {=[?]}, velocity differences present: {=[?]} }}",
            present(&self.baselines),
            present(&self.velocity_differences)
        );
    }
}

impl Format for FilterEstimate<f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "FilterEstimate {{ q_rb: {}, euler: {}, sigma (rad): {=[?]}, nis: {=f32} ({=u8} dof), health: {} }}",
            self.q_rb,
            self.euler,
            self.sigma().as_slice(),
            self.nis,
            self.nis_dof,
            self.health
        );
    }
}

impl Format for DirectionCosineModel<f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "DirectionCosineModel {{ eliminated column: {=usize}, normal ratio: {=f32} }}",
            self.eliminated_column(),
            self.normal_ratio()
        );
    }
}

impl Format for DirectionCosineFilter<f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "DirectionCosineFilter {{ {}, Y: {=[?]}, R (column-major): {=[?]} }}",
            self.model(),
            self.state().as_slice(),
            self.covariance().as_slice()
        );
    }
}

impl Format for MultiStructureEstimate<f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "MultiStructureEstimate {{ fused: {}, inliers: {=[?]} }}",
            self.fused, self.inliers
        );
    }
}

impl Format for MultiStructureFilter<f32> {
    fn format(&self, f: Formatter<'_>) {
        let [a, b, c] = self.structures();
        write!(f, "MultiStructureFilter {{ {}, {}, {} }}", a, b, c);
    }
}

impl Format for RigidBodyFilter<f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "RigidBodyFilter {{ q_rb: {}, rate (rad/s): {=[?]}, P (column-major): {=[?]} }}",
            self.attitude(),
            self.rate().as_slice(),
            self.covariance().as_slice()
        );
    }
}
