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

// ---- attitude (paper 002) -------------------------------------------------------------------

use crate::attitude::ambiguity::{
    AmbiguityFix, AmbiguityResolver, PhaseObservations, PhaseSatellite,
};
use crate::attitude::lambda::Decorrelation;
use crate::attitude::range_model::{
    BaselineCorrelation, Baselines, RangeDifferences, SatelliteRanges,
};
use crate::attitude::snapshot::{SnapshotSolution, SnapshotSolver};
use crate::attitude::wahba::{WahbaPair, WahbaProblem, WahbaSolution};

impl<const M: usize> Format for SatelliteRanges<M, f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "SatelliteRanges {{ id: {=u8}, los: {=[?]}, range_diff: {=[?]}, sigma: {=f32} }}",
            self.id,
            self.los.as_slice(),
            &self.range_diff[..],
            self.sigma
        );
    }
}

impl<const M: usize, const N: usize> Format for RangeDifferences<M, N, f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "RangeDifferences {{ {=[?]} }}", self.satellites());
    }
}

impl<const M: usize> Format for Baselines<M, f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "Baselines {{ b (body, m):");
        for b in self.as_array() {
            write!(f, " {=[?]}", b.as_slice());
        }
        write!(f, " }}");
    }
}

impl<const M: usize> Format for BaselineCorrelation<M, f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "BaselineCorrelation {{ {=[?]} }}",
            self.matrix().as_slice()
        );
    }
}

impl Format for WahbaPair<f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "WahbaPair {{ body: {=[?]}, reference: {=[?]}, weight: {=f32} }}",
            self.body.as_slice(),
            self.reference.as_slice(),
            self.weight
        );
    }
}

impl Format for WahbaProblem<f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "WahbaProblem");
    }
}

impl Format for WahbaSolution<f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "WahbaSolution {{ q_rb: {}, loss: {=f32}, eigen_gap: {=f32} }}",
            self.q_rb, self.loss, self.eigen_gap
        );
    }
}

impl Format for SnapshotSolution<f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "SnapshotSolution {{ q_rb: {}, euler: {}, covariance: {=[?]}, residual_rms: {=f32}, chi_square: {=f32}, dof: {=u16}, iterations: {=u8}, quality: {} }}",
            self.q_rb,
            self.euler,
            self.covariance.as_slice(),
            self.residual_rms,
            self.chi_square,
            self.dof,
            self.iterations,
            self.quality
        );
    }
}

impl<const M: usize> Format for SnapshotSolver<M, f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "SnapshotSolver {{ {}, {} }}",
            self.baselines(),
            self.correlation()
        );
    }
}

impl<const N: usize> Format for Decorrelation<N, f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "Decorrelation {{ n: {=usize}, d: {=[?]} }}",
            self.n,
            self.d.as_slice()
        );
    }
}

impl<const M: usize> Format for PhaseSatellite<M, f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "PhaseSatellite {{ id: {=u8}, los: {=[?]}, phase_cycles: {=[?]}, code_m: {=[?]}, cofactor: {=f32} }}",
            self.id,
            self.los.as_slice(),
            &self.phase_cycles[..],
            &self.code_m[..],
            self.cofactor
        );
    }
}

impl<const M: usize, const N: usize> Format for PhaseObservations<M, N, f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "PhaseObservations {{ {=[?]} }}", self.satellites());
    }
}

impl<const M: usize, const N: usize> Format for AmbiguityFix<M, N, f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "AmbiguityFix {{ ambiguities:");
        for row in &self.ambiguities {
            write!(f, " {=[?]}", &row[..]);
        }
        write!(
            f,
            ", solution: {}, cost: {=f32}, second_cost: {=f32}, ratio: {=f32}, nodes: {=u32}, candidates: {=u32} }}",
            self.solution,
            self.cost,
            self.second_cost,
            self.ratio,
            self.nodes,
            self.candidates
        );
    }
}

impl<const M: usize> Format for AmbiguityResolver<M, f32> {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "AmbiguityResolver {{ {} }}", self.config());
    }
}
use crate::attitude::array::AntennaArray;
use crate::attitude::baseline_epoch::BaselineEpoch;
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
            "AntennaArray {{ A: {=[?]}, B: {=[?]}, C: {=[?]} }}",
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

mod gyro {
    use defmt::{write, Format, Formatter};

    use crate::gyro::{
        AttitudePropagator, CalibrationEstimate, EpochEquations, EpochOutcome, ErrorQuadratures,
        GyroCalibrator, GyroErrorModel, LeastSquaresAccumulator, LsqSolution, NormalEquations,
        ObservabilityReport, PropagationStep, ReferenceDriftModel, SqrtInformation,
    };

    impl<const X: usize> Format for ObservabilityReport<X, f32> {
        fn format(&self, f: Formatter<'_>) {
            write!(
                f,
                "ObservabilityReport {{ rank: {=usize}, condition: {=f32}, equilibrated: {=f32}, singular values: {=[?]} }}",
                self.rank,
                self.condition,
                self.equilibrated_condition,
                self.singular_values.as_slice()
            );
        }
    }

    impl<const X: usize> Format for LsqSolution<X, f32> {
        fn format(&self, f: Formatter<'_>) {
            write!(
                f,
                "LsqSolution {{ x: {=[?]}, std_dev: {=[?]}, sigma0: {=f32}, rows: {=u32}, {} }}",
                self.x.as_slice(),
                self.std_dev.as_slice(),
                self.sigma0,
                self.rows,
                self.observability
            );
        }
    }

    impl<const X: usize> Format for SqrtInformation<X, f32> {
        fn format(&self, f: Formatter<'_>) {
            write!(
                f,
                "SqrtInformation {{ rows: {=u32}, rss: {=f32}, R (column-major): {=[?]}, y: {=[?]} }}",
                self.rows(),
                self.residual_sum_of_squares(),
                self.factor().as_slice(),
                self.rhs().as_slice()
            );
        }
    }

    impl<const X: usize> Format for NormalEquations<X, f32> {
        fn format(&self, f: Formatter<'_>) {
            write!(
                f,
                "NormalEquations {{ rows: {=u32}, UᵀZ: {=[?]} }}",
                self.rows(),
                self.rhs().as_slice()
            );
        }
    }

    impl<const CM: usize, const DN: usize> Format for ErrorQuadratures<CM, DN, f32> {
        fn format(&self, f: Formatter<'_>) {
            write!(
                f,
                "ErrorQuadratures {{ Θ (column-major): {=[?]}, ∫G: {=[?]}, K: {=[?]} }}",
                self.theta().as_slice(),
                self.g_integral().as_slice(),
                self.correction_integral().as_slice()
            );
        }
    }

    impl Format for AttitudePropagator<f32> {
        fn format(&self, f: Formatter<'_>) {
            write!(
                f,
                "AttitudePropagator {{ M: {}, mid_step: {=bool} }}",
                self.attitude(),
                self.mid_step()
            );
        }
    }

    impl Format for PropagationStep<f32> {
        fn format(&self, f: Formatter<'_>) {
            write!(
                f,
                "PropagationStep {{ increment: {=[?]}, rotation_vector: {=[?]} }}",
                self.increment.as_slice(),
                self.rotation_vector.as_slice()
            );
        }
    }

    impl<const X: usize> Format for EpochEquations<X, f32> {
        fn format(&self, f: Formatter<'_>) {
            write!(
                f,
                "EpochEquations {{ p0: {=f32}, rhs: {=[?]}, rows (column-major): {=[?]} }}",
                self.p0,
                self.rhs.as_slice(),
                self.rows.as_slice()
            );
        }
    }

    impl<const X: usize> Format for EpochOutcome<X, f32> {
        fn format(&self, f: Formatter<'_>) {
            match self {
                Self::Used(eq) => write!(f, "Used({})", eq),
                Self::Skipped(reason) => write!(f, "Skipped({})", reason),
            }
        }
    }

    impl<const CM: usize, const DN: usize, const X: usize> Format
        for CalibrationEstimate<CM, DN, X, f32>
    {
        fn format(&self, f: Formatter<'_>) {
            write!(
                f,
                "CalibrationEstimate {{ w0: {=[?]}, c: {=[?]}, d: {=[?]}, c_std: {=[?]}, d_std: {=[?]}, {} }}",
                self.w0.as_slice(),
                self.c.as_slice(),
                self.d.as_slice(),
                self.c_std.as_slice(),
                self.d_std.as_slice(),
                self.solution.observability
            );
        }
    }

    impl<G, R, A, const CM: usize, const DN: usize, const X: usize> Format
        for GyroCalibrator<G, R, A, CM, DN, X, f32>
    where
        G: GyroErrorModel<f32, CM>,
        R: ReferenceDriftModel<f32, DN>,
        A: LeastSquaresAccumulator<f32, X>,
    {
        fn format(&self, f: Formatter<'_>) {
            write!(
                f,
                "GyroCalibrator {{ elapsed: {=f32} s, M: {}, epochs: {}, rows: {=u32} }}",
                self.elapsed(),
                self.attitude(),
                self.counters(),
                self.accumulator().rows()
            );
        }
    }
}

mod one_stage {
    use defmt::{write, Format, Formatter};

    use crate::attitude::one_stage::{
        EpochInformation, OneStageFilter, PhaseDifferences, PhaseModel, Prior, SatelliteTerms,
    };

    impl Format for PhaseDifferences {
        fn format(&self, f: Formatter<'_>) {
            write!(
                f,
                "PhaseDifferences {{ epochs: {=u32}, cycles: {} }}",
                self.epochs(),
                self.phase_cycles()
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
}

mod receiver {
    use defmt::{write, Format, Formatter};

    use crate::receiver::{AttitudeReceiver, ReceiverAttitude, StageEstimate};

    impl Format for StageEstimate {
        fn format(&self, f: Formatter<'_>) {
            write!(
                f,
                "StageEstimate {{ epoch: {=u64}, q_rb: {}, covariance (column-major): {=[?]} }}",
                self.epoch,
                self.q_rb,
                self.covariance.as_slice()
            );
        }
    }

    impl Format for ReceiverAttitude {
        fn format(&self, f: Formatter<'_>) {
            write!(
                f,
                "ReceiverAttitude {{ epoch: {=u64}, source: {}, q_rb: {}, euler: {}, covariance (column-major): {=[?]}, health: {} }}",
                self.epoch,
                self.source,
                self.q_rb,
                self.euler,
                self.covariance.as_slice(),
                self.health
            );
        }
    }

    impl Format for AttitudeReceiver {
        fn format(&self, f: Formatter<'_>) {
            write!(f, "AttitudeReceiver {{ {} }}", self.attitude());
        }
    }
}
