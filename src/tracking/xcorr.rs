//! Cross-correlation between C/A signals: how much of a strong satellite's power one PRN's
//! correlator picks up at a given code lag and Doppler offset, and the test of whether a
//! detection or a tracked channel is explained by the stronger signals around it rather than
//! by a satellite of its own.
//!
//! # The model
//! A correlator for PRN `b` at code phase `τ_b` and carrier `f_b` integrating one code period
//! over a signal of PRN `a` (code phase `τ_a`, carrier `f_a`, power `S_a` at its own
//! correlator) sees the power `S_a · |R_ab|²` with
//!
//! ```text
//! R_ab = (1/1023) Σ_{k=0}^{1022} c_a(s + k) · [(1 − u) c_b(s + k + n) + u c_b(s + k + n + 1)]
//!                                 · e^{j2π Δf (k + ½ − frac s) / f_c}
//! ```
//! where `n + u = τ_b − τ_a` (integer and fractional lag, chips), `Δf = f_a − f_b`, `f_c` the
//! chip rate and `s` the chip of code `a` at which the integration starts (`τ_a` for a search
//! window that starts with the samples; `τ_a − τ_b` for a channel whose integration starts at
//! its own code epoch). `|R_ab|²` is at most −23.9 dB at `Δf = 0` (the Gold codes' three
//! values) and reaches about −21 dB at some Doppler offsets near multiples of 1 kHz, where the
//! product `c_a · e^{j2πΔf t}` is again periodic in the code period.
//!
//! # The test ([`cross_correlation_source`])
//! A victim (signal power `S_v`) is explained by the others when
//! `S_v ≤ margin · X_v` with `X_v = Σ_j X_j + 2 Σ_{j<j' coherent} √(X_j X_j')`, `X_j = S_j ·
//! (max|R_jv|² − ⅔/1023)⁺` over the others stronger than the victim (`S_j > S_v`), the maximum
//! taken over a small grid of lags and Doppler offsets around the nominal ones (the estimates'
//! errors). The victim's power has its background removed, and every background (the mean
//! cell of a search, a channel's noise tap) already holds the mean of `|R_jv|²` over code
//! lags, [`MEAN_FRACTION`]: only the excess at the victim's lag can make a peak. (Without
//! that, a real 45 dB-Hz satellite among eleven stronger ones up to 60 dB-Hz was predicted
//! within 2 dB of its own power and refused.)
//! Two others add coherently when their Doppler difference is within `coherence_hz` of a
//! multiple of 1 kHz (their relative phase then barely turns within the integration).
//! Bounded: `others.len()` × [`GRID_POINTS`] sums of 1023 terms, plus the pairs.

use crate::signal::ca_code::{Prn, CA_CHIP_RATE_HZ, CA_CODE_LENGTH};

/// Lag steps of the grid around the nominal lag, as fractions of the lag tolerance the caller
/// gives.
const GRID_LAG_FRACTIONS: [f64; 5] = [-1.0, -0.5, 0.0, 0.5, 1.0];

/// Doppler steps of the grid around the nominal Doppler offset, as fractions of the Doppler
/// tolerance the caller gives.
const GRID_DOPPLER_FRACTIONS: [f32; 3] = [-1.0, 0.0, 1.0];

/// Grid points of one cross-correlation maximum.
pub const GRID_POINTS: usize = GRID_LAG_FRACTIONS.len() * GRID_DOPPLER_FRACTIONS.len();

/// The mean of `|R_ab|²` over code lags, `(2/3)/1023`: the Gold codes' cross-correlation
/// energy spread over the code period (`1/1023` at whole-chip lags), times the `2/3` of
/// rectangular chips at fractional lags (a replica chip overlaps two chips of the other code
/// with fractions `u`, `1 − u`; the mean of `(1 − u)² + u²`). The part of a stronger signal's
/// cross-correlation every background estimate already holds.
pub const MEAN_FRACTION: f32 = 2.0 / (3.0 * CA_CODE_LENGTH as f32);

/// Most other signals one test considers (satellites in view of one antenna).
pub const MAX_OTHERS: usize = 32;

/// `|R_ab|²` (see the module documentation): the fraction of code `a`'s power that a
/// correlator of code `b` at lag `lag_chips = τ_b − τ_a` and Doppler offset
/// `doppler_offset_hz = f_a − f_b` picks up over one code period starting at chip
/// `start_chip_a` of code `a`. 1 for `a = b`, zero lag and offset. Bounded: 1023 terms.
pub fn code_cross_correlation(
    a: Prn,
    b: Prn,
    lag_chips: f64,
    start_chip_a: f64,
    doppler_offset_hz: f32,
) -> f32 {
    let [r] = cross_correlations(a, b, lag_chips, start_chip_a, [doppler_offset_hz]);
    r
}

/// [`code_cross_correlation`] at `D` Doppler offsets in one pass over the codes (each
/// offset's sums are the same sequence of operations as alone, so the results are equal bit
/// for bit). Non-finite inputs give 0.
fn cross_correlations<const D: usize>(
    a: Prn,
    b: Prn,
    lag_chips: f64,
    start_chip_a: f64,
    doppler_offsets_hz: [f32; D],
) -> [f32; D] {
    let (Some((n, u)), Some((first, frac))) = (split_chips(lag_chips), split_chips(start_chip_a))
    else {
        return [0.0; D];
    };
    if !doppler_offsets_hz.iter().all(|f| f.is_finite()) {
        return [0.0; D];
    }
    LagSums::new(a, b, n, first, frac, doppler_offsets_hz)
        .fraction(n, u)
        .unwrap_or([0.0; D])
}

/// A code phase or lag reduced modulo the code: whole chip `0 … 1022` and fraction `[0, 1)`;
/// `None` when not finite.
fn split_chips(chips: f64) -> Option<(usize, f32)> {
    if !chips.is_finite() {
        return None;
    }
    let len = CA_CODE_LENGTH as f64;
    let c = chips - libm::floor(chips / len) * len;
    let whole = libm::floor(c);
    Some((whole as usize % CA_CODE_LENGTH, (c - whole) as f32))
}

/// Integer lags one pass over the codes sums: a lag grid of half-width up to one chip (the
/// tracking channels' 0.25, an acquisition's 1023/N) touches at most four.
const LAG_WINDOW: usize = 4;

/// The window's chip products `1 − 2·(x ⊕ y)` for every pattern of differing chips (bit `l`
/// set where the two chips at lag `l` differ): four loads instead of four conversions.
const CHIP_PRODUCTS: [[f32; LAG_WINDOW]; 1 << LAG_WINDOW] = chip_products();

const fn chip_products() -> [[f32; LAG_WINDOW]; 1 << LAG_WINDOW] {
    let mut out = [[1.0f32; LAG_WINDOW]; 1 << LAG_WINDOW];
    let mut pattern = 0;
    while pattern < 1 << LAG_WINDOW {
        let mut l = 0;
        while l < LAG_WINDOW {
            if (pattern >> l) & 1 == 1 {
                out[pattern][l] = -1.0;
            }
            l += 1;
        }
        pattern += 1;
    }
    out
}

/// The complex sums `S(m) = Σ_k c_a(s + k) · c_b(s + k + m) · e^{jw(k + ½ − frac s)}` of
/// [`LAG_WINDOW`] consecutive integer lags `m = n0, n0 + 1, …` at `D` Doppler offsets, from
/// one pass over the codes. A fractional lag `n + u` is their interpolation,
/// `R = ((1 − u) S(n) + u S(n + 1)) / 1023` (the module's model is linear in the replica's two
/// chips), so a grid of lags costs one pass instead of one per lag.
struct LagSums<const D: usize> {
    /// First integer lag, chips.
    n0: usize,
    /// `(Re, Im)` of `S(n0 + l)` at each offset.
    sums: [[(f32, f32); D]; LAG_WINDOW],
}

impl<const D: usize> LagSums<D> {
    /// Sums lags `n0 …` over the code period starting at chip `first` of code `a` (chip
    /// centres at `½ − frac`). Bounded: 1023 chips × `D` × [`LAG_WINDOW`].
    fn new(a: Prn, b: Prn, n0: usize, first: usize, frac: f32, offsets_hz: [f32; D]) -> Self {
        let n0 = n0 % CA_CODE_LENGTH;
        let mut phasors = offsets_hz.map(|f| ChipPhasor::new(f, frac));
        let mut sums = [[(0.0f32, 0.0f32); D]; LAG_WINDOW];

        // the next chip index, wrapped by one comparison (indices stay below 1023; wrapping
        // arithmetic, so that no overflow check is left for the optimizer to discharge)
        let next = |i: usize| {
            let n = i.wrapping_add(1);
            if n >= CA_CODE_LENGTH {
                n.wrapping_sub(CA_CODE_LENGTH)
            } else {
                n
            }
        };
        let mut j = first % CA_CODE_LENGTH;
        // Code `b`'s logic chips at the window's lags, bit `l` = chip `j + n0 + l`, slid one
        // chip per step; `k` is the chip that enters next. A product of two chips is
        // `1 − 2·(x ⊕ y)` in logic values.
        let mut k = (j + n0) % CA_CODE_LENGTH;
        let mut window = 0u32;
        for l in 0..LAG_WINDOW {
            window |= u32::from(b.chip_bit(k)) << l;
            k = next(k);
        }
        for _ in 0..CA_CODE_LENGTH {
            let differ = window ^ 0u32.wrapping_sub(u32::from(a.chip_bit(j)));
            let products = CHIP_PRODUCTS
                .get((differ as usize) & (CHIP_PRODUCTS.len() - 1))
                .copied()
                .unwrap_or_default();
            for (d, ph) in phasors.iter_mut().enumerate() {
                for (lag, &p) in sums.iter_mut().zip(&products) {
                    if let Some(s) = lag.get_mut(d) {
                        s.0 += p * ph.pr;
                        s.1 += p * ph.pi;
                    }
                }
                ph.turn();
            }
            j = next(j);
            window = (window >> 1) | (u32::from(b.chip_bit(k)) << (LAG_WINDOW - 1));
            k = next(k);
        }
        Self { n0, sums }
    }

    /// `|R|²` at lag `n + u` for each offset; `None` when `n` and `n + 1` are not both in
    /// the window.
    fn fraction(&self, n: usize, u: f32) -> Option<[f32; D]> {
        // (n0 < 1023 from `new`)
        let l = (n % CA_CODE_LENGTH + CA_CODE_LENGTH - self.n0 % CA_CODE_LENGTH) % CA_CODE_LENGTH;
        let (s0, s1) = (self.sums.get(l)?, self.sums.get(l + 1)?);
        let scale = 1.0 / CA_CODE_LENGTH as f32;
        let mut out = [0.0f32; D];
        for ((o, a), b) in out.iter_mut().zip(s0).zip(s1) {
            let (re, im) = ((1.0 - u) * a.0 + u * b.0, (1.0 - u) * a.1 + u * b.1);
            *o = (re * re + im * im) * scale * scale;
        }
        Some(out)
    }
}

/// The phasor `e^{jw(k + ½ − frac)}` of one Doppler offset at chip `k`, `w` per chip.
#[derive(Clone, Copy)]
struct ChipPhasor {
    /// `cos w`, `sin w`.
    wc: f32,
    ws: f32,
    /// The phasor at the current chip.
    pr: f32,
    pi: f32,
}

impl ChipPhasor {
    /// Starts at chip centre `½ − frac` for an offset of `doppler_offset_hz`.
    fn new(doppler_offset_hz: f32, frac: f32) -> Self {
        let w = core::f32::consts::TAU * doppler_offset_hz / CA_CHIP_RATE_HZ as f32;
        let p0 = w * (0.5 - frac);
        Self {
            wc: libm::cosf(w),
            ws: libm::sinf(w),
            pr: libm::cosf(p0),
            pi: libm::sinf(p0),
        }
    }

    /// Turns the phasor by one chip.
    fn turn(&mut self) {
        let r = self.pr * self.wc - self.pi * self.ws;
        self.pi = self.pr * self.ws + self.pi * self.wc;
        self.pr = r;
    }
}

/// A signal as the cross-correlation test sees it: code phase and rate at a receiver sample,
/// Doppler, and its power at its own correlator (any unit, the same for every signal of one
/// test, with the background removed).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SignalProbe {
    /// The satellite.
    pub prn: Prn,
    /// Receiver sample index the code phase refers to.
    pub sample: u64,
    /// Code phase at `sample`, chips in `[0, 1023)`.
    pub code_phase_chips: f64,
    /// Code rate, chips per sample.
    pub code_chips_per_sample: f64,
    /// Doppler, Hz.
    pub doppler_hz: f32,
    /// Signal power at its own correlator (background removed), common unit.
    pub power: f32,
}

impl SignalProbe {
    /// Code phase at receiver sample `sample`, chips in `[0, 1023)`.
    pub fn code_phase_at(&self, sample: u64) -> f64 {
        let dt = (sample as i64).wrapping_sub(self.sample as i64) as f64;
        let c = self.code_phase_chips + dt * self.code_chips_per_sample;
        let len = CA_CODE_LENGTH as f64;
        c - libm::floor(c / len) * len
    }
}

/// How the victim's integration is aligned, and how uncertain the parameters are.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CrossCorrelationTest {
    /// `true`: the integration starts at the victim's code epochs (a tracking channel);
    /// `false`: at the victim's `sample` (an acquisition window).
    pub epoch_aligned: bool,
    /// Doppler uncertainty of the offsets, Hz (the grid's Doppler half-width).
    pub doppler_tolerance_hz: f32,
    /// Code-phase uncertainty of the lags, chips (the grid's lag half-width).
    pub lag_tolerance_chips: f64,
    /// Doppler difference (modulo 1 kHz) within which two others add coherently, Hz
    /// (about one over the integration time).
    pub coherence_hz: f32,
    /// The victim is explained when its power is at most this times the predicted one.
    pub margin: f32,
}

/// What the test found.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CrossCorrelationVerdict {
    /// The stronger signal that contributes most to the victim (`None`: none stronger).
    pub strongest_source: Option<Prn>,
    /// Predicted cross-correlation power at the victim's correlator (the victim's unit).
    pub predicted_power: f32,
    /// The victim's power is explained by the others (`power ≤ margin · predicted`).
    pub explained: bool,
}

/// The largest `|R|²` of `other` into the victim over the test's grid: one pass over the
/// codes ([`LagSums`]) for all the grid's lags and Doppler offsets (two for a lag grid wider
/// than the window).
fn largest_fraction(victim: &SignalProbe, other: &SignalProbe, test: &CrossCorrelationTest) -> f32 {
    let tau_a = other.code_phase_at(victim.sample);
    let tau_b = victim.code_phase_chips;
    let start = if test.epoch_aligned {
        tau_a - tau_b
    } else {
        tau_a
    };
    let offset = other.doppler_hz - victim.doppler_hz;
    let offsets = GRID_DOPPLER_FRACTIONS.map(|df| offset + df * test.doppler_tolerance_hz);
    let Some((first, frac)) = split_chips(start) else {
        return 0.0;
    };
    if !offsets.iter().all(|f| f.is_finite()) {
        return 0.0;
    }
    let mut window: Option<LagSums<{ GRID_DOPPLER_FRACTIONS.len() }>> = None;
    let mut best = 0.0f32;
    for &dl in &GRID_LAG_FRACTIONS {
        let Some((n, u)) = split_chips(tau_b - tau_a + dl * test.lag_tolerance_chips) else {
            continue;
        };
        let mut fraction = window.as_ref().and_then(|w| w.fraction(n, u));
        if fraction.is_none() {
            let w = LagSums::new(other.prn, victim.prn, n, first, frac, offsets);
            fraction = w.fraction(n, u);
            window = Some(w);
        }
        for r in fraction.unwrap_or_default() {
            best = best.max(r);
        }
    }
    best
}

/// Whether two Dopplers differ by nearly a multiple of 1 kHz (within `tolerance_hz`).
pub fn near_khz_multiple(a_hz: f32, b_hz: f32, tolerance_hz: f32) -> bool {
    let d = (a_hz - b_hz) / 1000.0;
    (d - libm::roundf(d)).abs() * 1000.0 <= tolerance_hz
}

/// The test of the module documentation: is `victim` explained by the cross-correlation of
/// the stronger ones among `others` (entries with the victim's PRN are skipped; at most
/// [`MAX_OTHERS`] are considered)? Bounded: see the module documentation.
pub fn cross_correlation_source(
    victim: &SignalProbe,
    others: &[SignalProbe],
    test: &CrossCorrelationTest,
) -> CrossCorrelationVerdict {
    let mut contributions = [(0.0f32, 0.0f32); MAX_OTHERS]; // (X_j, Doppler)
    let mut count = 0usize;
    let mut strongest: Option<(Prn, f32)> = None;
    let stronger = others
        .iter()
        .filter(|o| o.prn != victim.prn && o.power > victim.power && o.power.is_finite());
    for (slot, other) in contributions.iter_mut().zip(stronger) {
        let x = other.power * (largest_fraction(victim, other, test) - MEAN_FRACTION).max(0.0);
        *slot = (x, other.doppler_hz);
        count = count.saturating_add(1); // (at most MAX_OTHERS)
        if strongest.is_none_or(|(_, s)| x > s) {
            strongest = Some((other.prn, x));
        }
    }
    let used = contributions.get(..count).unwrap_or(&[]);
    let mut predicted: f32 = used.iter().map(|c| c.0).sum();
    for (k, a) in (0..used.len()).zip(used) {
        for b in used.iter().skip(k + 1) {
            if near_khz_multiple(a.1, b.1, test.coherence_hz) {
                predicted += 2.0 * crate::sqrtf(a.0 * b.0);
            }
        }
    }
    CrossCorrelationVerdict {
        strongest_source: strongest.map(|s| s.0),
        predicted_power: predicted,
        explained: count > 0 && victim.power <= test.margin * predicted,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signal::ca_code::cyclic_correlation;

    fn prn(n: u8) -> Prn {
        Prn::new(n).unwrap()
    }

    /// At zero Doppler offset and integer lags the model is the cyclic correlation of the
    /// codes (1 for the code with itself, the Gold codes' three values otherwise), whatever
    /// the start chip; half-chip lags average the neighbours.
    #[test]
    fn integer_lags_give_the_cyclic_correlation() {
        assert!((code_cross_correlation(prn(3), prn(3), 0.0, 17.0, 0.0) - 1.0).abs() < 1e-5);
        for lag in [0usize, 1, 100, 511, 1022] {
            let r = cyclic_correlation(prn(1), prn(2), lag) as f32 / 1023.0;
            let m = code_cross_correlation(prn(1), prn(2), lag as f64, 300.4, 0.0);
            assert!((m - r * r).abs() < 1e-6, "lag {lag}: {m} vs {}", r * r);
            assert!(r.abs() <= 65.0 / 1023.0);
        }
        let half = code_cross_correlation(prn(5), prn(5), 0.5, 0.0, 0.0);
        assert!((half - 0.25).abs() < 0.01, "{half}");
    }

    /// One pass over the codes for several Doppler offsets gives each offset's value alone,
    /// bit for bit (the test's grid relies on it).
    #[test]
    fn several_offsets_in_one_pass_equal_each_offset_alone() {
        for &(a, b, lag, start) in &[
            (1u8, 2u8, 17.3, 300.4),
            (7, 12, 1022.9, 0.0),
            (5, 5, 0.0, 511.5),
        ] {
            let offsets = [-1250.0f32, 3.5, 1999.0];
            let together = cross_correlations(prn(a), prn(b), lag, start, offsets);
            let alone = offsets.map(|f| code_cross_correlation(prn(a), prn(b), lag, start, f));
            assert_eq!(together.map(f32::to_bits), alone.map(f32::to_bits));
        }
    }

    /// Against a sample-level f64 correlation of the two codes with a Doppler offset (what a
    /// correlator computes at 16 samples per chip): the chip-level model agrees.
    #[test]
    fn the_model_matches_a_sample_level_correlation() {
        let per_chip = 16usize;
        for &(a, b, lag, start, df) in &[
            (4u8, 9u8, 37.3, 100.0, 1000.0f32),
            (4, 9, 800.75, 5.5, 3000.0),
            (17, 22, 12.0, 1000.2, 250.0),
            (1, 31, 511.5, 0.0, -2000.0),
        ] {
            let (pa, pb) = (prn(a), prn(b));
            let (mut sr, mut si) = (0.0f64, 0.0f64);
            let n = 1023 * per_chip;
            for k in 0..n {
                let t_chips = (k as f64 + 0.5) / per_chip as f64; // chips since window start
                let xa = start + t_chips;
                let xb = xa + lag;
                let ca = f64::from(pa.chip((xa.rem_euclid(1023.0)) as usize));
                let cb = f64::from(pb.chip((xb.rem_euclid(1023.0)) as usize));
                let ph = core::f64::consts::TAU * f64::from(df) * t_chips / 1.023e6;
                sr += ca * cb * ph.cos();
                si += ca * cb * ph.sin();
            }
            let exact = ((sr * sr + si * si) / (n * n) as f64) as f32;
            let model = code_cross_correlation(pa, pb, lag, start, df);
            assert!(
                (model - exact).abs() < 2e-4 + 0.02 * exact,
                "{a}/{b} lag {lag} df {df}: model {model}, exact {exact}"
            );
        }
    }

    fn probe(p: u8, tau: f64, doppler: f32, power: f32) -> SignalProbe {
        SignalProbe {
            prn: prn(p),
            sample: 1000,
            code_phase_chips: tau,
            code_chips_per_sample: 1.023e6 / 2.6e6,
            doppler_hz: doppler,
            power,
        }
    }

    /// The test's grid from one pass over the codes (a window of integer lags, interpolated)
    /// equals its lags and offsets taken one at a time, bit for bit: a tracking grid, an
    /// acquisition's (one chip wide), and grids across the code's wrap.
    #[test]
    fn the_grid_in_one_pass_equals_its_points_one_by_one() {
        let cases = [
            (100.2, 612.9, 0.25, true),
            (1022.6, 0.3, 1023.0 / 1024.0, false),
            (0.1, 1022.95, 0.25, false),
            (511.0, 3.75, 1023.0 / 1024.0, true),
        ];
        for (tau_v, tau_o, tol, aligned) in cases {
            let (victim, other) = (
                probe(7, tau_v, 1000.0, 1.0),
                probe(12, tau_o, 2210.0, 100.0),
            );
            let test = CrossCorrelationTest {
                epoch_aligned: aligned,
                lag_tolerance_chips: tol,
                ..TEST
            };
            let tau_a = other.code_phase_at(victim.sample);
            let start = if aligned { tau_a - tau_v } else { tau_a };
            let mut one_by_one = 0.0f32;
            for dl in GRID_LAG_FRACTIONS {
                for df in GRID_DOPPLER_FRACTIONS {
                    let offset =
                        other.doppler_hz - victim.doppler_hz + df * TEST.doppler_tolerance_hz;
                    let lag = tau_v - tau_a + dl * tol;
                    let r = code_cross_correlation(other.prn, victim.prn, lag, start, offset);
                    one_by_one = one_by_one.max(r);
                }
            }
            let grid = largest_fraction(&victim, &other, &test);
            assert!(grid > 0.0);
            assert_eq!(
                grid.to_bits(),
                one_by_one.to_bits(),
                "{tau_v} {tau_o} {tol}: {grid} vs {one_by_one}"
            );
        }
    }

    const TEST: CrossCorrelationTest = CrossCorrelationTest {
        epoch_aligned: false,
        doppler_tolerance_hz: 100.0,
        lag_tolerance_chips: 0.25,
        coherence_hz: 50.0,
        margin: 2.0,
    };

    /// A victim at the strongest cross-correlation peak of a strong signal, with the power
    /// that peak gives, is explained; the same victim ten times stronger, or a victim with
    /// no stronger signal around, is not.
    #[test]
    fn a_victim_at_a_cross_correlation_peak_is_explained() {
        let strong = probe(7, 100.0, 1200.0, 1.0e6);
        // Find the victim lag with the largest |R|² at 1 kHz offset.
        let (mut best, mut at) = (0.0f32, 0.0f64);
        for l in 0..1023 {
            let r = code_cross_correlation(prn(7), prn(12), f64::from(l), 100.0, 1000.0);
            if r > best {
                best = r;
                at = f64::from(l);
            }
        }
        assert!(best > 10f32.powf(-2.6), "{best}");
        let victim = probe(12, (100.0 + at) % 1023.0, 200.0, 1.0e6 * best);
        let v = cross_correlation_source(&victim, &[strong], &TEST);
        assert!(v.explained, "{v:?}");
        assert_eq!(v.strongest_source, Some(prn(7)));
        let real = SignalProbe {
            power: 10.0 * victim.power,
            ..victim
        };
        assert!(!cross_correlation_source(&real, &[strong], &TEST).explained);
        let alone = cross_correlation_source(&victim, &[], &TEST);
        assert!(!alone.explained && alone.strongest_source.is_none());
    }
    /// A real 45 dB-Hz satellite among eleven stronger ones (46–60 dB-Hz: a synthesized
    /// static sky, truth code phases and Dopplers) is not explained: the others' mean
    /// cross-correlation is in the background already; only their excess at its lag counts.
    #[test]
    fn a_weak_real_satellite_among_many_strong_ones_is_not_explained() {
        let sky: [(u8, f32, f32, f64); 12] = [
            (2, 58.64, -4021.9, 830.43),
            (6, 46.36, -809.2, 459.68),
            (7, 49.09, 2363.9, 252.49),
            (10, 53.18, 976.2, 1012.85),
            (12, 55.91, -2978.6, 242.10),
            (15, 54.55, 3046.9, 676.52),
            (19, 50.45, -1268.6, 630.50),
            (22, 57.27, 3354.8, 952.61),
            (25, 51.82, -4381.3, 218.46),
            (26, 60.00, -4342.4, 168.19),
            (28, 45.00, -4178.4, 990.46),
            (30, 47.73, -2954.6, 436.82),
        ];
        let probes = sky.map(|(p, cn0, f, tau)| SignalProbe {
            sample: 0,
            ..probe(p, tau, f, 10f32.powf(cn0 / 10.0))
        });
        let test = CrossCorrelationTest {
            doppler_tolerance_hz: 125.0,
            lag_tolerance_chips: 1023.0 / 2048.0,
            ..TEST
        };
        for victim in probes.iter().filter(|p| p.power < 10f32.powf(4.7)) {
            let v = cross_correlation_source(victim, &probes, &test);
            assert!(!v.explained, "PRN {}: {v:?}", victim.prn.number());
            // room over the margin (3 dB) for a measured power's straddle losses
            assert!(victim.power > 3.0 * v.predicted_power, "{v:?}");
        }
    }
}
