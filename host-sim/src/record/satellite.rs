//! The per-satellite state of `track`: lock bookkeeping, 100 ms rows, C/N0 reports, the
//! Doppler-rate fit and the attitude sums, fed one epoch at a time; and the thermal C/N0
//! (the other satellites' cross-correlation removed).

use gnss_attitude::tracking::channel::Cn0Estimate;
use gnss_attitude::tracking::{ChannelState, SearchResult, TrackingEpoch};
use serde::Serialize;

use super::attitude::PhaseAccumulator;
use super::navigation::NavChannel;
use super::track::{PULL_IN_ALLOWANCE_S, REACQUIRE_AFTER_S, ROW_INTERVAL_S};

/// One 100 ms row of a satellite.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Row {
    /// End of the interval, s from the first sample.
    pub t_s: f64,
    /// Mean replica Doppler over the interval, Hz.
    pub doppler_hz: f64,
    /// Latest C/N0 report, dB-Hz.
    pub cn0_dbhz: f64,
    /// Fraction of the interval's epochs with code and phase lock.
    pub locked: f64,
}

/// The per-satellite report.
#[derive(Clone, Debug, Serialize)]
pub struct SatelliteReport {
    /// PRN.
    pub prn: u8,
    /// Doppler of the first acquisition, Hz.
    pub acquired_doppler_hz: f64,
    /// Code phase of the first acquisition (at the first sample), chips.
    pub acquired_code_phase_chips: f64,
    /// First epoch with code and phase lock, s (`None`: never locked).
    pub first_lock_s: Option<f64>,
    /// Total time with code and phase lock, s.
    pub lock_time_s: f64,
    /// Longest uninterrupted lock, s.
    pub longest_lock_s: f64,
    /// Locked without a break from the first lock to the end of the run.
    pub held_to_end: bool,
    /// Lock losses after the first lock.
    pub losses: u32,
    /// Re-acquisitions (successful hand-overs after a loss).
    pub reacquisitions: u32,
    /// Mean of the 1 s C/N0 reports from 2 s on (all reports if fewer; the channel's last
    /// estimate, from its 100 ms lock windows, when the run is shorter than one report:
    /// `cn0_short_window`), dB-Hz.
    pub cn0_dbhz_mean: f64,
    /// Smallest and largest of those reports, dB-Hz.
    pub cn0_dbhz_range: [f64; 2],
    /// `cn0_dbhz_mean` with the modelled cross-correlation of the other tracked satellites
    /// removed (see [`mai_corrected_cn0`]): the thermal C/N0, dB-Hz.
    pub cn0_dbhz_thermal: f64,
    /// Doppler rate by least squares over the locked epochs, Hz/s.
    pub doppler_rate_hz_s: f64,
    /// Doppler over time: one value per second (mean of the locked epochs), Hz; `null` for
    /// seconds without lock.
    pub doppler_hz_per_s: Vec<Option<f64>>,
    /// C/N0 reports over time (one per second after the first), dB-Hz.
    pub cn0_dbhz_per_s: Vec<f64>,
    /// Seconds of samples `cn0_dbhz_mean` rests on (0 without an estimate).
    pub cn0_basis_s: f64,
    /// `cn0_dbhz_mean` rests on less than one second (no 1 s report).
    pub cn0_short_window: bool,
    /// The noise estimate was no more than the samples' quantization explains (a noise-free
    /// recording), at some point while locked: the C/N0 is then the signal over the rounding
    /// noise (or its floor), not over thermal noise.
    pub cn0_quantization_limited: bool,
    /// Times the channel released itself as another satellite's cross-correlation.
    pub cross_correlation_releases: u32,
    /// When it first did, s (`None`: never).
    pub first_cross_correlation_release_s: Option<f64>,
}

/// The running state of one satellite (the companion of its channel).
pub struct SatTrack {
    pub(super) prn: u8,
    pub(super) first: SearchResult,
    pub(super) fs: f64,
    pub(super) active: bool,
    pub(super) started_t: f64,
    pub(super) last_lock_t: f64,
    pub(super) last_t: f64,
    pub(super) reacquisitions: u32,
    pub(super) retry_at: f64,
    // lock bookkeeping
    first_lock: Option<f64>,
    pub(super) run_start: Option<f64>,
    pub(super) longest: f64,
    locked_epochs: u64,
    pub(super) losses: u32,
    // rows
    rows: Vec<Row>,
    row_end: f64,
    row_sum: (f64, u32, u32, u32), // Σ Doppler (locked), locked count, epochs, Σ-count of Doppler
    cn0_last: f64,
    cn0_reports: Vec<(f64, f64)>,
    // Doppler-rate least squares over locked epochs: Σ1, Σt, Σt², Σf, Σtf
    fit: [f64; 5],
    // the channel's C/N0 estimate after the last block, and whether one was quantization
    // limited while locked
    cn0_estimate: Cn0Estimate,
    cn0_quantization_limited: bool,
    cross_correlation_releases: u32,
    first_release: Option<f64>,
    /// Phase and code sums of the attitude windows.
    pub phases: Option<PhaseAccumulator>,
    /// The channel's navigation decoder and measurements.
    pub nav: Option<NavChannel>,
}

impl SatTrack {
    pub(super) fn new(first: SearchResult, fs: f64, phases: Option<PhaseAccumulator>) -> Self {
        Self {
            prn: first.prn.number(),
            first,
            fs,
            active: true,
            started_t: 0.0,
            last_lock_t: 0.0,
            last_t: 0.0,
            reacquisitions: 0,
            retry_at: 0.0,
            first_lock: None,
            run_start: None,
            longest: 0.0,
            locked_epochs: 0,
            losses: 0,
            rows: Vec::new(),
            row_end: ROW_INTERVAL_S,
            row_sum: (0.0, 0, 0, 0),
            cn0_last: f64::NAN,
            cn0_reports: Vec::new(),
            fit: [0.0; 5],
            cn0_estimate: Cn0Estimate::default(),
            cn0_quantization_limited: false,
            cross_correlation_releases: 0,
            first_release: None,
            phases,
            nav: None,
        }
    }

    /// Notes the channel's C/N0 estimate after a block.
    pub(super) fn note_cn0(&mut self, e: Cn0Estimate) {
        if e.cn0_dbhz > 0.0 {
            self.cn0_estimate = e;
            if self.run_start.is_some() && e.quantization_limited {
                self.cn0_quantization_limited = true;
            }
        }
    }

    /// Stops the satellite after its channel released itself as a cross-correlation; it is
    /// searched again from `retry_at` (s).
    pub(super) fn release_as_cross_correlation(&mut self, now: f64, retry_at: f64) {
        self.first_release.get_or_insert(now);
        self.active = false;
        self.retry_at = retry_at;
        self.cross_correlation_releases += 1;
        if let Some(run) = self.run_start.take() {
            self.longest = self.longest.max(self.last_t - run);
            self.losses += 1;
        }
    }

    /// PRN.
    pub fn prn(&self) -> u8 {
        self.prn
    }

    pub(super) fn epoch<const A: usize>(&mut self, e: &TrackingEpoch<A>) {
        let c = &e.correlations;
        let t = (c.first_sample as f64 + 0.5 * f64::from(c.samples)) / self.fs;
        let dt = f64::from(c.samples) / self.fs;
        while t > self.row_end {
            self.close_row();
        }
        // The lock detector also runs during the refinement stage, whose carrier loop is open:
        // lock counts from the pull-in on.
        let locked = e.lock.code && e.lock.phase && e.state != ChannelState::Refining;
        if locked {
            self.last_lock_t = t;
        }
        let doppler = f64::from(e.doppler_hz);
        self.row_sum.2 += 1;
        if locked {
            self.row_sum.0 += doppler;
            self.row_sum.1 += 1;
            self.locked_epochs += 1;
            for (s, v) in self
                .fit
                .iter_mut()
                .zip([1.0, t, t * t, doppler, t * doppler])
            {
                *s += v;
            }
            if self.first_lock.is_none() {
                self.first_lock = Some(t - 0.5 * dt);
            }
            if self.run_start.is_none() {
                self.run_start = Some(t - 0.5 * dt);
            }
        } else if let Some(s) = self.run_start.take() {
            self.longest = self.longest.max(t - 0.5 * dt - s);
            self.losses += 1;
        }
        // 0 until the channel's first lock window completes: no estimate yet.
        self.cn0_last = if e.cn0_dbhz > 0.0 {
            f64::from(e.cn0_dbhz)
        } else {
            f64::NAN
        };
        // A fresh 1 s C/N0 report completes with every 1000th epoch since the hand-over.
        if (e.index + 1) % 1000 == 0 {
            self.cn0_reports.push((t, self.cn0_last));
        }
        if let Some(p) = self.phases.as_mut() {
            p.add(e, t, locked);
        }
        if let Some(n) = self.nav.as_mut() {
            n.epoch(e, locked);
        }
        self.last_t = t + 0.5 * dt;
    }

    fn close_row(&mut self) {
        let (sum, locked, n, _) = self.row_sum;
        self.rows.push(Row {
            t_s: self.row_end,
            doppler_hz: if locked > 0 {
                sum / f64::from(locked)
            } else {
                f64::NAN
            },
            cn0_dbhz: self.cn0_last,
            locked: if n > 0 {
                f64::from(locked) / f64::from(n)
            } else {
                0.0
            },
        });
        self.row_sum = (0.0, 0, 0, 0);
        self.row_end += ROW_INTERVAL_S;
    }

    pub(super) fn needs_reacquisition(&self, now: f64) -> bool {
        let since = self.last_lock_t.max(self.started_t + PULL_IN_ALLOWANCE_S);
        self.active && now - since > REACQUIRE_AFTER_S
    }

    pub(super) fn report(&mut self, end_t: f64) -> SatelliteReport {
        while self.row_end <= end_t + 1e-9 {
            self.close_row();
        }
        if self.row_sum.2 > 0 {
            self.close_row();
        }
        let held = self.run_start.is_some() && self.losses == 0;
        if let Some(s) = self.run_start {
            self.longest = self.longest.max(self.last_t - s);
        }
        let late: Vec<f64> = self
            .cn0_reports
            .iter()
            .filter(|(t, _)| *t >= 2.0)
            .map(|r| r.1)
            .collect();
        let reports: Vec<f64> = if late.is_empty() {
            self.cn0_reports.iter().map(|r| r.1).collect()
        } else {
            late
        };
        let mean = reports.iter().sum::<f64>() / reports.len().max(1) as f64;
        // Shorter than one report: the channel's last estimate (from its lock windows).
        let short = reports.is_empty() && self.cn0_estimate.cn0_dbhz > 0.0;
        let last = f64::from(self.cn0_estimate.cn0_dbhz);
        let range = reports
            .iter()
            .fold([f64::INFINITY, f64::NEG_INFINITY], |r, &c| {
                [r[0].min(c), r[1].max(c)]
            });
        let [n, st, stt, sf, stf] = self.fit;
        let det = n * stt - st * st;
        let rate = if n > 10.0 && det > 1e-12 {
            (n * stf - st * sf) / det
        } else {
            f64::NAN
        };
        let per_s = |rows: &[Row]| -> Vec<Option<f64>> {
            rows.chunks(10)
                .map(|c| {
                    let v: Vec<f64> = c
                        .iter()
                        .map(|r| r.doppler_hz)
                        .filter(|d| d.is_finite())
                        .collect();
                    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
                })
                .collect()
        };
        SatelliteReport {
            prn: self.prn,
            acquired_doppler_hz: f64::from(self.first.doppler_hz),
            acquired_code_phase_chips: f64::from(self.first.code_phase_chips),
            first_lock_s: self.first_lock,
            lock_time_s: self.locked_epochs as f64 * 1e-3,
            longest_lock_s: self.longest,
            held_to_end: held,
            losses: self.losses,
            reacquisitions: self.reacquisitions,
            cn0_dbhz_mean: match (reports.is_empty(), short) {
                (false, _) => mean,
                (true, true) => last,
                (true, false) => f64::NAN,
            },
            cn0_dbhz_range: match (reports.is_empty(), short) {
                (false, _) => range,
                (true, true) => [last; 2],
                (true, false) => [f64::NAN; 2],
            },
            cn0_dbhz_thermal: f64::NAN,
            doppler_rate_hz_s: rate,
            doppler_hz_per_s: per_s(&self.rows),
            cn0_dbhz_per_s: self.cn0_reports.iter().map(|r| r.1).collect(),
            cn0_basis_s: if short {
                (f64::from(self.cn0_estimate.window_s) * 1e3).round() / 1e3
            } else {
                reports.len() as f64
            },
            cn0_short_window: short,
            cn0_quantization_limited: self.cn0_quantization_limited,
            cross_correlation_releases: self.cross_correlation_releases,
            first_cross_correlation_release_s: self.first_release,
        }
    }

    /// The rows (100 ms) so far.
    pub fn rows(&self) -> &[Row] {
        &self.rows
    }
}

/// Spectral separation coefficient of two GPS C/A (BPSK-R(1)) signals with rectangular chips
/// and no band limit, 1/Hz: `κ = ∫ G(f)² df = 2/(3 f_c)` (−61.9 dB/Hz). A 1 ms prompt sees
/// another satellite's code at a random fractional chip offset `u`; its cross-correlation power
/// is `((1 − u)² + u²)/1023` on average over the code, i.e. `(2/3)/1023` over `u`.
pub const CA_SPECTRAL_SEPARATION_PER_HZ: f64 = 2.0 / (3.0 * gnss_attitude::signal::CA_CHIP_RATE_HZ);

/// Thermal C/N0 from the measured ones (dB-Hz; NaN entries are skipped): the noise tap and the
/// prompt both see the other satellites' cross-correlation, so the core's estimator measures
/// `C_i/(N0 + I0_i)` with `I0_i = κ Σ_{j≠i} C_j` (the effective C/N0 of Betz's spectral
/// separation coefficient, `κ` = [`CA_SPECTRAL_SEPARATION_PER_HZ`]). Solved for the thermal
/// values by a fixed-point iteration (10 steps; it contracts by `κ Σ C/N0 ≪ 1`). Satellites
/// that are not tracked are not in the sum; a band-limited front end has a somewhat smaller
/// `κ`. Capped at the core's largest C/N0 (99 dB-Hz): without thermal noise (a noise-free
/// recording) the measured noise is all cross-correlation and the thermal C/N0 unbounded.
pub fn mai_corrected_cn0(measured_dbhz: &[f64]) -> Vec<f64> {
    const MAX_CN0: f64 = gnss_attitude::tracking::cn0::MAX_CN0_DBHZ as f64;
    let kappa = CA_SPECTRAL_SEPARATION_PER_HZ;
    let x: Vec<f64> = measured_dbhz
        .iter()
        .map(|c| {
            if c.is_finite() {
                10f64.powf(c / 10.0)
            } else {
                0.0
            }
        })
        .collect();
    let mut thermal = x.clone();
    for _ in 0..10 {
        let sum: f64 = thermal.iter().map(|c| c * kappa).sum();
        thermal = x
            .iter()
            .zip(&thermal)
            .map(|(&xi, &ti)| xi * (1.0 + sum - ti * kappa))
            .collect();
    }
    measured_dbhz
        .iter()
        .zip(thermal)
        .map(|(m, t)| {
            if m.is_finite() {
                (10.0 * t.log10()).min(MAX_CN0)
            } else {
                f64::NAN
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::mai_corrected_cn0;

    /// Two satellites at 50 dB-Hz: each sees I0/N0 = 10⁵ · 2/(3 · 1.023·10⁶) = 0.0652, so the
    /// measured value is 50 − 10 log10(1.0652) = 49.726 dB-Hz; the correction returns 50.
    /// A lone satellite is unchanged; NaN stays NaN and is not counted.
    #[test]
    fn mai_correction_inverts_the_model() {
        let measured = 50.0 - 10.0 * (1.0 + 1e5 * 2.0 / 3.0 / 1.023e6f64).log10();
        let c = mai_corrected_cn0(&[measured, measured, f64::NAN]);
        assert!(
            (c[0] - 50.0).abs() < 1e-3 && (c[1] - 50.0).abs() < 1e-3,
            "{c:?}"
        );
        assert!(c[2].is_nan());
        assert_eq!(mai_corrected_cn0(&[43.0]), vec![43.0]);
    }
}
