//! The one-stage filter on `X = [α; α̇]` (plus optional line biases): prediction (7)/(10)/(11)
//! and the update in either form, Gaussian approximation (9)/(12) or constant gains.

use nalgebra::{Cholesky, Matrix3, SMatrix, SVector, Vector3};

use crate::ekf::Ekf;
use crate::geometry::Paper003Angles;
use crate::{real, OneStageError, Real};

use super::array::{AntennaArray, PhaseModel};
use super::config::{FilterMode, OneStageConfig, ProcessNoise};
use super::information::{epoch_information, EpochInformation, PARAMETERS};
use super::input::{CheckedObservation, SatelliteObservation, MAX_SATELLITES};
use super::lock::{LockDetector, LockStatus};
use super::prior::Prior;

/// State dimension: α, β, γ, α̇, β̇, γ̇, `b_B`, `b_C`.
pub const STATES: usize = 8;
/// Where each parameter of `θ = [α, β, γ, b_B, b_C]` sits in the state (`c` of eq. (9)).
const PARAMETER_INDEX: [usize; PARAMETERS] = [0, 1, 2, 6, 7];

/// What one epoch did.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EpochReport<T = f32> {
    /// Satellites used.
    pub satellites: u8,
    /// The lock detector's verdict after this epoch. Use the attitude only when `Locked`.
    pub status: LockStatus,
    /// Smoothed alignment `η̄` (1 at the true peak, see [`super::lock`]).
    pub alignment: T,
    /// The lock detector's settle statistic `s` (χ² scale, see [`super::lock`]).
    pub settle_statistic: T,
    /// The angle discriminator `u_α` of eq. (32) at the predicted state, 1/rad (α, β, γ;
    /// zero for angles not estimated).
    pub angle_discriminator: [T; 3],
    /// The correction the update applied to the angles, rad.
    pub angle_step: [T; 3],
    /// Satellites whose observed curvature needed the floor (Gaussian mode).
    pub curvature_floored: u8,
}

/// The one-stage coherent–noncoherent attitude filter of paper 003.
///
/// Every epoch it takes the prompt I/Q of the three antennas for each tracked satellite
/// ([`SatelliteObservation`]) and moves the attitude angles (eq. (2)), their rates and the
/// optional line biases so as to climb the likelihood `Σ_i ln I₀(a X_i)` of eq. (15), in which
/// the common carrier phase and the data bit are averaged out. No per-satellite state is
/// kept: satellites may appear and disappear from one epoch to the next.
///
/// The state is `X = [α, β, γ, α̇, β̇, γ̇, b_B, b_C]` (rad, rad/s, rad); angles not estimated
/// and the biases when they are off are held at their prior values with unit variance and no
/// coupling. Angles are wrapped to `(−π, π]`.
#[derive(Clone, Debug, PartialEq)]
pub struct OneStageFilter<T = f32> {
    config: OneStageConfig<T>,
    array: AntennaArray<T>,
    ekf: Ekf<STATES, T>,
    lock: LockDetector<T>,
    /// Last scheduled process-noise densities per parameter (Gaussian mode), kept for epochs
    /// without information.
    scheduled_psd: [T; PARAMETERS],
}

fn el<T: Real, const R: usize, const C: usize>(m: &SMatrix<T, R, C>, i: usize, j: usize) -> T {
    m.get((i, j)).copied().unwrap_or_else(T::zero)
}

fn set<T: Real, const R: usize, const C: usize>(
    m: &mut SMatrix<T, R, C>,
    i: usize,
    j: usize,
    v: T,
) {
    if let Some(e) = m.get_mut((i, j)) {
        *e = v;
    }
}

/// `angle` wrapped to `(−π, π]`.
fn wrap<T: Real>(angle: T) -> T {
    let pi = T::pi();
    if angle > -pi && angle <= pi {
        return angle;
    }
    let two_pi = T::two_pi();
    let w = angle - two_pi * ((angle + pi) / two_pi).floor();
    if w <= -pi {
        w + two_pi
    } else {
        w
    }
}

/// `L̃` with `W = L̃ L̃ᵀ` for a symmetric positive semi-definite `W` (`LDLᵀ` without pivoting,
/// pivots below `1e-6 · max diag` taken as zero, so a singular `W` gives zero columns):
/// `N` outer steps, bounded.
fn psd_factor<T: Real, const N: usize>(w: &SMatrix<T, N, N>) -> SMatrix<T, N, N> {
    let max_diag = w.diagonal().iter().fold(T::zero(), |m, &v| m.max(v));
    let tol = max_diag * real(1e-6);
    let mut l = SMatrix::<T, N, N>::zeros();
    let mut d = SVector::<T, N>::zeros();
    for j in 0..N {
        let mut dj = el(w, j, j);
        for k in 0..j {
            let ljk = el(&l, j, k);
            dj -= ljk * ljk * d.get(k).copied().unwrap_or_else(T::zero);
        }
        if !(dj > tol) {
            continue;
        }
        if let Some(v) = d.get_mut(j) {
            *v = dj;
        }
        set(&mut l, j, j, T::one());
        for i in (j + 1)..N {
            let mut s = el(w, i, j);
            for k in 0..j {
                s -= el(&l, i, k) * el(&l, j, k) * d.get(k).copied().unwrap_or_else(T::zero);
            }
            set(&mut l, i, j, s / dj);
        }
    }
    l * SMatrix::from_diagonal(&d.map(|v| v.sqrt()))
}

/// Solves `(J + εI) x = b` by Cholesky, `ε = 1e-4 · max diag` (a pseudo-inverse for the
/// unobservable directions of a singular `J`); zero when even that fails.
fn regularized_solve<T: Real, const N: usize>(
    j: &SMatrix<T, N, N>,
    b: &SVector<T, N>,
) -> SVector<T, N> {
    let max_diag = j.diagonal().iter().fold(T::zero(), |m, &v| m.max(v));
    let reg = j + SMatrix::<T, N, N>::identity() * (max_diag * real(1e-4) + real(1e-30));
    Cholesky::new(reg).map_or_else(SVector::zeros, |c| c.solve(b))
}

/// `1/(J⁻¹)_kk` for every parameter with information (`J_kk > 0`), zero for the others (whose
/// rows and columns are replaced by the identity before the factorization). The same
/// regularization as [`regularized_solve`].
fn marginal_information<T: Real, const N: usize>(j: &SMatrix<T, N, N>) -> SVector<T, N> {
    let max_diag = j.diagonal().iter().fold(T::zero(), |m, &v| m.max(v));
    let mut m = *j + SMatrix::<T, N, N>::identity() * (max_diag * real(1e-4));
    let has = j.diagonal().map(|v| v > T::zero());
    for k in 0..N {
        if !has.get(k).copied().unwrap_or(false) {
            m.row_mut(k).fill(T::zero());
            m.column_mut(k).fill(T::zero());
            set(&mut m, k, k, T::one());
        }
    }
    let Some(chol) = Cholesky::new(m) else {
        return SVector::zeros();
    };
    let inv = chol.inverse();
    SVector::from_fn(|k, _| {
        let d = el(&inv, k, k);
        if has.get(k).copied().unwrap_or(false) && d > T::zero() {
            d.recip()
        } else {
            T::zero()
        }
    })
}

impl<T: Real> OneStageFilter<T> {
    /// A filter for `array` started from `prior`.
    ///
    /// # Errors
    /// [`OneStageError::InvalidConfig`] when [`OneStageConfig::is_valid`] fails; the errors of
    /// the prior ([`OneStageError::NonFiniteInput`], [`OneStageError::InvalidCovariance`]).
    pub fn new(
        config: OneStageConfig<T>,
        array: AntennaArray<T>,
        prior: &Prior<T>,
    ) -> Result<Self, OneStageError> {
        if !config.is_valid() {
            return Err(OneStageError::InvalidConfig);
        }
        let ekf = Self::initial_state(&config, prior)?;
        Ok(Self {
            lock: LockDetector::new(&config.lock, config.epoch_s),
            config,
            array,
            ekf,
            scheduled_psd: [T::zero(); PARAMETERS],
        })
    }

    /// Restarts from a new prior (a snapshot solution, or the caller's after a false lock),
    /// keeping the configuration; the lock detector returns to pull-in.
    ///
    /// # Errors
    /// As [`Self::new`] for the prior; the filter is then unchanged.
    pub fn reinitialize(&mut self, prior: &Prior<T>) -> Result<(), OneStageError> {
        self.ekf = Self::initial_state(&self.config, prior)?;
        self.lock.restart();
        Ok(())
    }

    fn active(config: &OneStageConfig<T>) -> [bool; PARAMETERS] {
        let [a, b, g] = config.estimate.as_array();
        let lb = config.line_bias_states;
        [a, b, g, lb, lb]
    }

    fn initial_state(
        config: &OneStageConfig<T>,
        prior: &Prior<T>,
    ) -> Result<Ekf<STATES, T>, OneStageError> {
        prior.check(config.line_bias_states)?;
        let angles = config.estimate.as_array();
        let mut x = SVector::<T, STATES>::zeros();
        let mut p = SMatrix::<T, STATES, STATES>::identity();
        let a = [prior.angles.alpha, prior.angles.beta, prior.angles.gamma];
        for (i, (&ai, &on_i)) in a.iter().zip(angles.iter()).enumerate() {
            x[i] = wrap(ai);
            if !on_i {
                continue;
            }
            x[3 + i] = prior.rates.get(i).copied().unwrap_or_else(T::zero);
            for (j, &on_j) in angles.iter().enumerate() {
                if on_j {
                    set(&mut p, i, j, el(&prior.angle_covariance, i, j));
                    set(&mut p, 3 + i, 3 + j, el(&prior.rate_covariance, i, j));
                }
            }
        }
        if config.line_bias_states {
            let [b_b, b_c] = prior.line_bias;
            let [v_b, v_c] = prior.line_bias_variance;
            (x[6], x[7]) = (b_b, b_c);
            (p[(6, 6)], p[(7, 7)]) = (v_b, v_c);
        }
        Ekf::new(x, p).map_err(|_| OneStageError::InvalidCovariance)
    }

    /// Transition `F` of eq. (8) for the estimated angles (held angles have no rate).
    fn transition(&self) -> SMatrix<T, STATES, STATES> {
        let mut f = SMatrix::<T, STATES, STATES>::identity();
        for (i, &on) in self.config.estimate.as_array().iter().enumerate() {
            if on {
                set(&mut f, i, 3 + i, self.config.epoch_s);
            }
        }
        f
    }

    /// One epoch: prediction (eq. (10)), the discriminators at the predicted state, the update
    /// of the configured [`FilterMode`], the lock detector. An empty slice only predicts.
    ///
    /// # Errors
    /// [`OneStageError::TooManySatellites`] for more than [`MAX_SATELLITES`];
    /// [`OneStageError::NonFiniteInput`] or [`OneStageError::InvalidObservation`] when any
    /// observation is unusable (drop that channel and call again);
    /// [`OneStageError::Numerical`] when the step fails numerically. On error the filter is
    /// unchanged.
    pub fn step(
        &mut self,
        observations: &[SatelliteObservation<T>],
    ) -> Result<EpochReport<T>, OneStageError> {
        // eq. (10): X̃ = F X̂
        let f = self.transition();
        let x_pred = f * self.ekf.state();
        let info = self.information_at(&x_pred, observations)?;

        // the normalized angle discriminator v = J_αα⁻¹ u_α (conditional on the biases)
        let j_aa: Matrix3<T> = info.expected.fixed_view::<3, 3>(0, 0).into_owned();
        let u_a: Vector3<T> = info.gradient.fixed_rows::<3>(0).into_owned();
        let normalized = regularized_solve(&j_aa, &u_a);

        let mut next = self.clone();
        match self.config.mode {
            FilterMode::GaussianApproximation => next.gaussian_update(&f, &x_pred, &info)?,
            FilterMode::ConstantGain => next.constant_gain_update(&x_pred, &info, &normalized)?,
        }
        let mut x = *next.ekf.state();
        for i in 0..3 {
            x[i] = wrap(x[i]);
        }
        next.ekf
            .set_state(x)
            .map_err(|_| OneStageError::Numerical)?;
        next.lock.update(
            info.coherent_power,
            info.aligned_power,
            info.satellites,
            &normalized,
            &j_aa,
        );
        let step = |i: usize| {
            let d = x[i] - x_pred[i];
            if self
                .config
                .estimate
                .as_array()
                .get(i)
                .copied()
                .unwrap_or(false)
            {
                wrap(d)
            } else {
                T::zero()
            }
        };
        let report = EpochReport {
            satellites: info.satellites,
            status: next.lock.status(),
            alignment: next.lock.alignment(),
            settle_statistic: next.lock.settle_statistic(),
            angle_discriminator: [info.gradient[0], info.gradient[1], info.gradient[2]],
            angle_step: [step(0), step(1), step(2)],
            curvature_floored: info.floored,
        };
        *self = next;
        Ok(report)
    }

    /// The epoch's discriminators and information (masked to the estimated parameters) at the
    /// state `x`.
    fn information_at(
        &self,
        x: &SVector<T, STATES>,
        observations: &[SatelliteObservation<T>],
    ) -> Result<EpochInformation<T>, OneStageError> {
        if observations.len() > MAX_SATELLITES {
            return Err(OneStageError::TooManySatellites);
        }
        let mut checked = heapless::Vec::<CheckedObservation<T>, MAX_SATELLITES>::new();
        for obs in observations {
            let c = obs.check(self.config.epoch_s)?;
            checked
                .push(c)
                .map_err(|_| OneStageError::TooManySatellites)?;
        }
        let angles = Paper003Angles::new(x[0], x[1], x[2]);
        let model = PhaseModel::new(&self.array, self.config.wavelength_m, &angles);
        let mut info =
            epoch_information(&model, [x[6], x[7]], &checked, self.config.curvature_floor);
        mask(&mut info, &Self::active(&self.config));
        Ok(info)
    }

    /// The discriminators and information of `observations` at the current estimate, without
    /// changing the filter (diagnostics; [`Self::step`] evaluates them at the predicted state).
    ///
    /// # Errors
    /// As [`Self::step`] for the observations.
    pub fn information(
        &self,
        observations: &[SatelliteObservation<T>],
    ) -> Result<EpochInformation<T>, OneStageError> {
        self.information_at(self.ekf.state(), observations)
    }

    /// Eqs. (11), (12), (9): `D̃ = F D Fᵀ + G D_ξ Gᵀ`, `D⁻¹ = D̃⁻¹ + cᵀ W c` with
    /// `W = −∂²F/∂θ∂θᵀ` (floored), `X̂ = X̃ + D cᵀ u`. The information update is done in
    /// covariance form with the toolkit's Joseph update: `W = L̃ L̃ᵀ`, pseudo-measurement
    /// rows `H = L̃ᵀ c` with unit noise, which gives exactly `(D̃⁻¹ + Hᵀ H)⁻¹`.
    fn gaussian_update(
        &mut self,
        f: &SMatrix<T, STATES, STATES>,
        x_pred: &SVector<T, STATES>,
        info: &EpochInformation<T>,
    ) -> Result<(), OneStageError> {
        let q = self.process_noise(info);
        self.ekf
            .predict_to(x_pred, f, &q)
            .map_err(|_| OneStageError::Numerical)?;
        if info.satellites == 0 {
            return Ok(());
        }
        let l = psd_factor(&info.observed);
        let mut h = SMatrix::<T, PARAMETERS, STATES>::zeros();
        for (k, &col) in PARAMETER_INDEX.iter().enumerate() {
            // H = L̃ᵀ c: column `col` of H is row k of L̃ᵀ, i.e. column k of L̃ transposed
            h.set_column(col, &l.row(k).transpose());
        }
        self.ekf
            .update(
                &SVector::<T, PARAMETERS>::zeros(),
                &h,
                &SMatrix::identity(),
                None,
            )
            .map_err(|_| OneStageError::Numerical)?;
        // eq. (9): X̂ = X̃ + D_X cᵀ u
        let mut ct_u = SVector::<T, STATES>::zeros();
        for (k, &col) in PARAMETER_INDEX.iter().enumerate() {
            ct_u[col] = info.gradient[k];
        }
        let x = x_pred + self.ekf.covariance() * ct_u;
        self.ekf.set_state(x).map_err(|_| OneStageError::Numerical)
    }

    /// `G D_ξ Gᵀ` of eq. (11) for this epoch (see [`ProcessNoise`]).
    fn process_noise(&mut self, info: &EpochInformation<T>) -> SMatrix<T, STATES, STATES> {
        let t = self.config.epoch_s;
        let active = Self::active(&self.config);
        let psd: [T; PARAMETERS] = match self.config.process_noise {
            ProcessNoise::Fixed {
                accel_psd,
                bias_psd,
            } => {
                let [qa, qb, qg] = accel_psd;
                [qa, qb, qg, bias_psd, bias_psd]
            }
            ProcessNoise::Bandwidth => {
                let wn = self.config.natural_frequency();
                let wb = self.config.bias_bandwidth_hz * real(4.0);
                // marginal information of each angle (biases known) and of each bias (all
                // else unknown), as the constant-gain loop's normalization sees them
                let j_aa: Matrix3<T> = info.expected.fixed_view::<3, 3>(0, 0).into_owned();
                let angles = marginal_information(&j_aa);
                let all = marginal_information(&info.expected);
                for (k, slot) in self.scheduled_psd.iter_mut().enumerate() {
                    let j = if k < 3 { angles.get(k) } else { all.get(k) };
                    // information rate J / T, 1/rad²/s
                    let rate = j.copied().unwrap_or_else(T::zero) / t;
                    if rate > T::zero() && rate.is_finite() {
                        *slot = if k < 3 {
                            wn * wn * wn * wn / rate // q = ω_n⁴ / J
                        } else {
                            wb * wb / rate // q_b = (4 Δf_b)² / J
                        };
                    }
                }
                self.scheduled_psd
            }
        };
        let mut q = SMatrix::<T, STATES, STATES>::zeros();
        for (k, (&on, &qk)) in active.iter().zip(psd.iter()).enumerate() {
            if on {
                // state k + 3: the rate of angle k (eq. (7): v_k = v_{k−1} + ξ) for k < 3, the
                // bias itself (states 6, 7) for k = 3, 4
                set(&mut q, k + 3, k + 3, qk * t);
            }
        }
        q
    }

    /// The constant-gain loop: `u_n = J_T⁻¹ u`, then `α̂ = α̃ + K1 u_n`, `v̂ = ṽ + K2 u_n`,
    /// `b̂ = b̃ + K_b u_{n,b}`. The angles' normalization is conditional on the biases
    /// (`J_αα⁻¹ u_α`), the biases' is joint (`(J⁻¹u)_b`), so that the bias loop sees unit slope
    /// and the angle loop the noise of known biases.
    fn constant_gain_update(
        &mut self,
        x_pred: &SVector<T, STATES>,
        info: &EpochInformation<T>,
        un_a: &Vector3<T>,
    ) -> Result<(), OneStageError> {
        let mut x = *x_pred;
        if info.satellites > 0 {
            let (k1, k2) = self.config.loop_gains();
            let kb = self.config.bias_gain();
            for i in 0..3 {
                x[i] += k1 * un_a[i];
                x[3 + i] += k2 * un_a[i];
            }
            if self.config.line_bias_states {
                let un = regularized_solve(&info.expected, &info.gradient);
                x[6] += kb * un[3];
                x[7] += kb * un[4];
            }
        }
        self.ekf.set_state(x).map_err(|_| OneStageError::Numerical)
    }

    /// The configuration.
    pub fn config(&self) -> &OneStageConfig<T> {
        &self.config
    }

    /// The antenna array.
    pub fn array(&self) -> &AntennaArray<T> {
        &self.array
    }

    /// The estimated angles α, β, γ of eq. (2), rad.
    pub fn angles(&self) -> Paper003Angles<T> {
        let x = self.ekf.state();
        Paper003Angles::new(x[0], x[1], x[2])
    }

    /// The estimated attitude `C_rb = U(α)` (body to reference).
    pub fn attitude(&self) -> Matrix3<T> {
        self.angles().to_dcm()
    }

    /// The estimated rates (α̇, β̇, γ̇), rad/s.
    pub fn rates(&self) -> Vector3<T> {
        self.ekf.state().fixed_rows::<3>(3).into_owned()
    }

    /// The estimated line biases `b_B`, `b_C`, rad (zero when not estimated).
    pub fn line_bias(&self) -> [T; 2] {
        let x = self.ekf.state();
        [x[6], x[7]]
    }

    /// The covariance of the estimated angles (rad², zero rows for held angles) in the
    /// Gaussian-approximation mode; `None` for the constant-gain loop, which has none.
    pub fn angle_covariance(&self) -> Option<Matrix3<T>> {
        if self.config.mode != FilterMode::GaussianApproximation {
            return None;
        }
        let mut c: Matrix3<T> = self.ekf.covariance().fixed_view::<3, 3>(0, 0).into_owned();
        for (i, &on) in self.config.estimate.as_array().iter().enumerate() {
            if !on {
                c.row_mut(i).fill(T::zero());
                c.column_mut(i).fill(T::zero());
            }
        }
        Some(c)
    }

    /// The full state `[α, β, γ, α̇, β̇, γ̇, b_B, b_C]` and, in the Gaussian mode, its covariance.
    pub fn estimate(&self) -> &Ekf<STATES, T> {
        &self.ekf
    }

    /// The lock detector's verdict.
    pub fn lock_status(&self) -> LockStatus {
        self.lock.status()
    }
}

/// Zeroes the information of parameters that are not estimated.
fn mask<T: Real>(info: &mut EpochInformation<T>, active: &[bool; PARAMETERS]) {
    for (k, &on) in active.iter().enumerate() {
        if !on {
            info.gradient[k] = T::zero();
            info.observed.row_mut(k).fill(T::zero());
            info.observed.column_mut(k).fill(T::zero());
            info.expected.row_mut(k).fill(T::zero());
            info.expected.column_mut(k).fill(T::zero());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::attitude::one_stage::{EstimatedAngles, PromptIq};
    use nalgebra::Matrix4;

    fn los(az_deg: f64, el_deg: f64) -> [f64; 3] {
        let (az, el) = (az_deg.to_radians(), el_deg.to_radians());
        [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()]
    }

    /// Noise-free observations of G1 at attitude `truth`, with per-satellite common phases.
    fn observations(
        truth: &Paper003Angles<f64>,
        n: usize,
    ) -> heapless::Vec<SatelliteObservation<f64>, MAX_SATELLITES> {
        let array = AntennaArray::paper_triangle(1.5).unwrap();
        let model = PhaseModel::new(&array, super::super::GPS_L1_WAVELENGTH_M, truth);
        let amp = (2.0 * 10.0f64).sqrt(); // 40 dB-Hz, T = 1 ms, σ = 1
        let mut out = heapless::Vec::new();
        for i in 0..n {
            let l = los(45.0 * i as f64, 10.0 * (i + 1) as f64);
            let psi = model.phases(&Vector3::from(l));
            let phi = 0.7 * i as f64;
            let mut prompt = PromptIq::default();
            for p in 0..3 {
                prompt.i[p] = amp * (phi + psi[p]).cos();
                prompt.q[p] = amp * (phi + psi[p]).sin();
            }
            let o = SatelliteObservation {
                id: i as u8 + 1,
                los: l,
                prompt,
                noise_var: 1.0,
                cn0_dbhz: 40.0,
            };
            out.push(o).unwrap();
        }
        out
    }

    #[test]
    fn psd_factor_reproduces_definite_and_singular_matrices() {
        let a = nalgebra::Matrix4x2::new(1.0, 2.0, -1.0, 0.5, 3.0, 0.0, 0.2, -2.0);
        let singular: Matrix4<f64> = a * a.transpose(); // rank 2
        let definite = singular + Matrix4::identity() * 0.3;
        for w in [singular, definite, Matrix4::zeros()] {
            let l = psd_factor(&w);
            assert!((l * l.transpose() - w).norm() < 1e-9 * (1.0 + w.norm()));
        }
    }

    #[test]
    fn wrap_maps_onto_minus_pi_to_pi() {
        use core::f64::consts::PI;
        for (a, w) in [
            (0.5, 0.5),
            (PI, PI),
            (-PI, PI),
            (3.0 * PI, PI),
            (7.0, 7.0 - 2.0 * PI),
        ] {
            assert!((wrap(a) - w).abs() < 1e-12, "{a}");
        }
    }

    #[test]
    fn gaussian_update_is_the_information_form_of_eq_12() {
        // one step from a static prior with fixed process noise: D⁻¹ = D̃⁻¹ + cᵀ W c and
        // X̂ = X̃ + D cᵀ u, computed here independently with plain inverses (f64, 8×8)
        let mut config = OneStageConfig::<f64>::gps_l1(FilterMode::GaussianApproximation, 2.0);
        config.process_noise = ProcessNoise::Fixed {
            accel_psd: [1e-4, 2e-4, 3e-4],
            bias_psd: 1e-6,
        };
        config.line_bias_states = true;
        let array = AntennaArray::paper_triangle(1.5).unwrap();
        let prior_angles = Paper003Angles::new(0.01, -0.02, 0.015);
        let mut prior = Prior::new(prior_angles, 0.02, 0.001);
        prior.line_bias_variance = [0.01, 0.02];
        let mut f = OneStageFilter::new(config, array, &prior).unwrap();
        let obs = observations(&Paper003Angles::new(0.0, 0.0, 0.0), 8);
        let info = f.information(&obs).unwrap(); // rates are zero: predicted = current
        let d_pred = f.transition() * f.ekf.covariance() * f.transition().transpose() + {
            let mut q = SMatrix::<f64, 8, 8>::zeros();
            for (k, v) in [1e-4, 2e-4, 3e-4, 1e-6, 1e-6].iter().enumerate() {
                q[(k + 3, k + 3)] = v * 1e-3;
            }
            q
        };
        let mut c = SMatrix::<f64, PARAMETERS, STATES>::zeros();
        for (k, &col) in PARAMETER_INDEX.iter().enumerate() {
            c[(k, col)] = 1.0;
        }
        let info_post = d_pred.try_inverse().unwrap() + c.transpose() * info.observed * c;
        let d_post = info_post.try_inverse().unwrap();
        let x_post = f.ekf.state() + d_post * c.transpose() * info.gradient;
        f.step(&obs).unwrap();
        assert!((f.ekf.covariance() - d_post).norm() < 1e-9 * d_post.norm());
        assert!((f.ekf.state() - x_post).norm() < 1e-9);
    }

    #[test]
    fn noise_free_data_pull_all_three_angles_in_with_either_form() {
        let truth = Paper003Angles::new(0.004, -0.006, 0.003);
        let obs = observations(&truth, 8);
        for mode in [FilterMode::GaussianApproximation, FilterMode::ConstantGain] {
            let config = OneStageConfig::<f64>::gps_l1(mode, 2.0);
            let array = AntennaArray::paper_triangle(1.5).unwrap();
            let prior = Prior::new(Paper003Angles::new(0.0, 0.0, 0.0), 0.01, 0.001);
            let mut f = OneStageFilter::new(config, array, &prior).unwrap();
            let mut last = None;
            for _ in 0..8000 {
                last = Some(f.step(&obs).unwrap());
            }
            let a = f.angles();
            for (e, t) in [
                (a.alpha, truth.alpha),
                (a.beta, truth.beta),
                (a.gamma, truth.gamma),
            ] {
                assert!((e - t).abs() < 1e-6, "{mode:?}: {e} vs {t}");
            }
            assert_eq!(last.unwrap().status, LockStatus::Locked);
            assert!(f.rates().norm() < 1e-6);
        }
    }

    #[test]
    fn invalid_configuration_and_prior_are_rejected() {
        let array = AntennaArray::<f32>::paper_triangle(1.5).unwrap();
        let prior = Prior::new(Paper003Angles::new(0.0, 0.0, 0.0), 0.01, 0.001);
        let good = OneStageConfig::<f32>::gps_l1(FilterMode::ConstantGain, 2.0);
        let mut bad = good;
        bad.estimate = EstimatedAngles {
            alpha: false,
            beta: false,
            gamma: false,
        };
        assert_eq!(
            OneStageFilter::new(bad, array, &prior).err(),
            Some(OneStageError::InvalidConfig)
        );
        let mut bad = good;
        bad.loop_bandwidth_hz = f32::NAN;
        assert!(OneStageFilter::new(bad, array, &prior).is_err());
        let mut bad_prior = prior;
        bad_prior.angle_covariance.m22 = -1.0;
        assert_eq!(
            OneStageFilter::new(good, array, &bad_prior).err(),
            Some(OneStageError::InvalidCovariance)
        );
        let mut f = OneStageFilter::new(good, array, &prior).unwrap();
        let before = f.clone();
        bad_prior.angles.beta = f32::INFINITY;
        assert_eq!(
            f.reinitialize(&bad_prior),
            Err(OneStageError::NonFiniteInput)
        );
        assert_eq!(f, before);
        // an empty epoch only predicts
        assert_eq!(f.step(&[]).unwrap().satellites, 0);
    }
}
