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
