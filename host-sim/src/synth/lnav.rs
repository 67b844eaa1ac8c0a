//! The GPS LNAV navigation message the synthesized satellites broadcast (IS-GPS-200 20.3):
//! ephemerides derived from the orbits of the bundled almanac, clock terms, subframes 1–5 with
//! the word parity, TOW/HOW counting, the 25-page rotation of subframes 4 and 5, and the data
//! bit of any satellite at any time.
//!
//! # The orbits are the truth's
//!
//! [`crate::truth::gps::AlmanacEntry::position_velocity`] propagates the almanac's Keplerian
//! elements (no harmonic terms) at `n0 = √(μ/A³)`. Each two-hour issue of the ephemeris
//! describes exactly that orbit, up to the LNAV scale factors: `√A` quantized and the mean
//! motion kept by `Δn = n0(A) − n0(A_q)`, `M0` and `Ω0` carried from the almanac's epoch to
//! `t_oe` (`Ω0` also through the `−Ω̇e t_oe` term of the user algorithm), `ω`, `i0`, `e`, `Ω̇`
//! copied, harmonic corrections and `IDOT` zero. Quantization leaves centimetres over the
//! ±1 h an issue is used (the test reports the figure).
//!
//! # The clocks
//!
//! [`ClockModel::Almanac`] broadcasts the almanac's `a_f0`, `a_f1` (carried to `t_oc`) and a
//! small per-PRN `T_GD`; [`ClockModel::Zero`] broadcasts zeros. Either way the satellite's L1
//! C/A signal leaves at signal time `t + Δt_sv(t)` ([`LnavEncoder::signal_clock_offset_s`]):
//! the broadcast clock polynomial, the relativistic term `F e √A sin E` (up to 23 ns for
//! e = 0.02, which every user applies) and `−T_GD`. A sample synthesizer that wants the
//! receiver's pseudoranges to match must delay the code and the data by that offset.
//!
//! # Independence
//!
//! The parity and the packing are written here from IS-GPS-200 Table 20-XIV and Figure 20-1
//! without the core's decoder, so that decoding this with `gnss_attitude::nav` is a test of
//! both. No kept crate encodes LNAV (the Rust GNSS crates decode RINEX, not navigation bits).

use crate::truth::gps::{Almanac, AlmanacEntry, MU, OMEGA_EARTH, WEEK_S};

/// IS-GPS-200's π for semicircles (the specification's value, not `std::f64::consts::PI`).
#[allow(clippy::approx_constant)]
pub const GPS_PI: f64 = 3.141_592_653_589_8;
/// Relativistic constant `F = −2√μ/c²`, s/√m.
pub const F_RELATIVISTIC: f64 = -4.442_807_633e-10;
/// Interval between ephemeris issues (and their `t_oe` spacing), s.
pub const ISSUE_S: f64 = 7200.0;
/// Seconds per subframe.
pub const SUBFRAME_S: f64 = 6.0;
/// Seconds per data bit.
pub const BIT_S: f64 = 0.02;
/// The TLM preamble.
pub const PREAMBLE: u32 = 0b1000_1011;

/// SV IDs of the 25 pages of subframe 4 (IS-GPS-200 Table 20-V): almanacs of SV 25–32 on
/// pages 2–5 and 7–10, 56 = ionosphere and UTC (page 18), 63 = A-S flags and health of
/// SV 25–32 (page 25), the others reserved or special.
const SUBFRAME4_SV_IDS: [u8; 25] = [
    57, 25, 26, 27, 28, 57, 29, 30, 31, 32, 57, 62, 52, 53, 54, 57, 55, 56, 58, 59, 57, 60, 61, 62,
    63,
];

/// Where the broadcast clock terms come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClockModel {
    /// `a_f0 = a_f1 = a_f2 = T_GD = 0` (the signal still carries the relativistic term).
    Zero,
    /// The almanac's `a_f0`, `a_f1` and a per-PRN `T_GD` of a few nanoseconds.
    Almanac,
}

/// Ionosphere (Klobuchar) and UTC parameters of subframe 4 page 18, in their units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IonoUtc {
    /// `α0 … α3`, s, s/semicircle, s/semicircle², s/semicircle³.
    pub alpha: [f64; 4],
    /// `β0 … β3`, s, s/semicircle, …
    pub beta: [f64; 4],
    /// `A0`, s.
    pub a0_s: f64,
    /// `A1`, s/s.
    pub a1: f64,
    /// `t_ot`, s (multiple of 4096).
    pub tot_s: u32,
    /// `Δt_LS`, s.
    pub delta_t_ls_s: i8,
    /// Day number of the next leap second.
    pub day_number: u8,
    /// `Δt_LSF`, s.
    pub delta_t_lsf_s: i8,
}

impl Default for IonoUtc {
    /// A typical broadcast set (mid solar activity) and the 18 s of leap seconds of 2022.
    fn default() -> Self {
        Self {
            alpha: [1.1176e-8, 7.4506e-9, -5.9605e-8, -5.9605e-8],
            beta: [90_112.0, 16_384.0, -196_608.0, -131_072.0],
            a0_s: 1.862_645_149_230_957e-9,
            a1: 3.552_713_678_800_501e-15,
            tot_s: 233_472,
            delta_t_ls_s: 18,
            day_number: 7,
            delta_t_lsf_s: 18,
        }
    }
}

/// One broadcast ephemeris as the satellite sends it: the values after quantization (what a
/// decoder recovers), RINEX 3 names and units (radians, seconds, metres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BroadcastEphemeris {
    /// PRN.
    pub prn: u8,
    /// Full GPS week of `t_oe`.
    pub week: u16,
    /// `t_oe`, s of the week.
    pub toe_s: f64,
    /// `t_oc`, s of the week.
    pub toc_s: f64,
    /// IODE.
    pub iode: u8,
    /// IODC (its low 8 bits are the IODE).
    pub iodc: u16,
    /// Six-bit health.
    pub health: u8,
    /// `√A`, √m.
    pub sqrt_a: f64,
    /// Eccentricity.
    pub e: f64,
    /// `i0`, rad.
    pub i0: f64,
    /// `Ω0`, rad.
    pub omega0: f64,
    /// `ω`, rad.
    pub omega: f64,
    /// `M0`, rad.
    pub m0: f64,
    /// `Δn`, rad/s.
    pub delta_n: f64,
    /// `Ω̇`, rad/s.
    pub omega_dot: f64,
    /// `a_f0`, s.
    pub af0: f64,
    /// `a_f1`, s/s.
    pub af1: f64,
    /// `T_GD`, s.
    pub tgd: f64,
    /// The integers sent, in the order of [`Quantized`].
    pub raw: Quantized,
}

impl BroadcastEphemeris {
    /// The ephemeris as the core's decoder assembles it from the subframes (URA index 0, fit
    /// interval 4 h, harmonic corrections, `IDOT` and `a_f2` zero as sent).
    pub fn to_core(&self) -> gnss_attitude::nav::Ephemeris {
        gnss_attitude::nav::Ephemeris {
            prn: self.prn,
            week: self.week,
            toe_s: self.toe_s,
            toc_s: self.toc_s,
            iode: self.iode,
            iodc: self.iodc,
            health: self.health,
            ura_index: 0,
            fit_interval: false,
            sqrt_a: self.sqrt_a,
            e: self.e,
            i0: self.i0,
            omega0: self.omega0,
            omega: self.omega,
            m0: self.m0,
            delta_n: self.delta_n,
            idot: 0.0,
            omega_dot: self.omega_dot,
            cuc: 0.0,
            cus: 0.0,
            crc: 0.0,
            crs: 0.0,
            cic: 0.0,
            cis: 0.0,
            af0: self.af0,
            af1: self.af1,
            af2: 0.0,
            tgd: self.tgd,
        }
    }
}

/// The integer fields of an ephemeris (two's complement where signed).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Quantized {
    /// `√A` / 2⁻¹⁹.
    pub sqrt_a: u32,
    /// `e` / 2⁻³³.
    pub e: u32,
    /// `i0` / 2⁻³¹ semicircles.
    pub i0: i32,
    /// `Ω0` / 2⁻³¹ semicircles.
    pub omega0: i32,
    /// `ω` / 2⁻³¹ semicircles.
    pub omega: i32,
    /// `M0` / 2⁻³¹ semicircles.
    pub m0: i32,
    /// `Δn` / 2⁻⁴³ semicircles/s.
    pub delta_n: i32,
    /// `Ω̇` / 2⁻⁴³ semicircles/s.
    pub omega_dot: i32,
    /// `a_f0` / 2⁻³¹ s.
    pub af0: i32,
    /// `a_f1` / 2⁻⁴³.
    pub af1: i32,
    /// `T_GD` / 2⁻³¹ s.
    pub tgd: i32,
    /// `t_oe` / 16 s.
    pub toe: u32,
}

/// The encoder: the almanac (orbits and clocks of the truth), its full week, the clock model
/// and the page-18 parameters.
#[derive(Clone, Debug)]
pub struct LnavEncoder {
    /// The almanac whose orbits the ephemerides describe.
    pub almanac: Almanac,
    /// Full GPS week of the almanac's seconds of the week (the truth's time origin).
    pub almanac_week: u16,
    /// Clock terms.
    pub clock: ClockModel,
    /// Page 18.
    pub iono_utc: IonoUtc,
}

/// Full GPS week of the bundled almanac (week 147 modulo 1024 of the second rollover epoch).
pub const BUNDLED_ALMANAC_WEEK: u16 = 2195;

fn pow2(n: i32) -> f64 {
    2f64.powi(n)
}

/// `x` rounded to a multiple of `2^scale` and checked against a `bits`-wide signed field.
fn quantize_signed(x: f64, scale: i32, bits: u32) -> i32 {
    let q = (x / pow2(scale)).round();
    let limit = f64::from(1u32 << (bits - 1));
    q.clamp(-limit, limit - 1.0) as i32
}

fn quantize_unsigned(x: f64, scale: i32, bits: u32) -> u32 {
    let q = (x / pow2(scale)).round();
    q.clamp(0.0, (2f64).powi(bits as i32) - 1.0) as u32
}

/// An angle wrapped into `[−π, π)` (IS-GPS-200 π) and quantized in semicircles.
fn quantize_angle(rad: f64, scale: i32, bits: u32) -> i32 {
    let mut sc = rad / GPS_PI;
    sc -= 2.0 * ((sc + 1.0) / 2.0).floor();
    quantize_signed(sc, scale, bits)
}

fn angle_of(q: i32, scale: i32) -> f64 {
    f64::from(q) * pow2(scale) * GPS_PI
}

impl LnavEncoder {
    /// The bundled almanac's encoder with the almanac's clocks.
    pub fn bundled() -> Self {
        Self {
            almanac: Almanac::bundled(),
            almanac_week: BUNDLED_ALMANAC_WEEK,
            clock: ClockModel::Almanac,
            iono_utc: IonoUtc::default(),
        }
    }

    fn entry(&self, prn: u8) -> Option<&AlmanacEntry> {
        self.almanac.entries.iter().find(|e| e.prn == prn)
    }

    /// Seconds since the start of the almanac's week.
    fn tau(&self, week: u16, tow_s: f64) -> f64 {
        (f64::from(week) - f64::from(self.almanac_week)) * WEEK_S + tow_s
    }

    /// The per-PRN group delay broadcast with [`ClockModel::Almanac`], s: a few ns,
    /// deterministic.
    pub fn tgd_s(&self, prn: u8) -> f64 {
        match self.clock {
            ClockModel::Zero => 0.0,
            ClockModel::Almanac => (f64::from(prn % 9) - 4.0) * 2.0 * pow2(-31),
        }
    }

    /// The truth's clock polynomial at `tau` (s from the almanac week's start).
    fn clock_poly(&self, entry: &AlmanacEntry, tau: f64) -> (f64, f64) {
        match self.clock {
            ClockModel::Zero => (0.0, 0.0),
            ClockModel::Almanac => (entry.af0 + entry.af1 * (tau - entry.toa_s), entry.af1),
        }
    }

    /// The ephemeris issue in effect at GPS time (`week`, `tow_s`): issue `k` covers
    /// `[k·2 h, (k+1)·2 h)` of the week with `t_oe` in its middle.
    pub fn ephemeris(&self, prn: u8, week: u16, tow_s: f64) -> Option<BroadcastEphemeris> {
        let entry = self.entry(prn)?;
        let tau = self.tau(week, tow_s);
        let issue = (tau / ISSUE_S).floor();
        let tau_toe = issue * ISSUE_S + ISSUE_S / 2.0;
        let toe_week_offset = (tau_toe / WEEK_S).floor();
        let toe_week = (f64::from(self.almanac_week) + toe_week_offset) as u16;
        let toe_s = tau_toe - toe_week_offset * WEEK_S;
        // √A quantized; Δn keeps the truth's mean motion n0 = √(μ/A³)
        let sqrt_a = quantize_unsigned(entry.sqrt_a, -19, 32);
        let a_q = (f64::from(sqrt_a) * pow2(-19)).powi(2);
        let a = entry.sqrt_a * entry.sqrt_a;
        let n0 = (MU / (a * a * a)).sqrt();
        let delta_n = quantize_signed((n0 - (MU / (a_q * a_q * a_q)).sqrt()) / GPS_PI, -43, 16);
        // the almanac's propagation time to t_oe (the truth wraps it within half a week)
        let mut since_toa = tau_toe - entry.toa_s;
        if since_toa > WEEK_S / 2.0 {
            since_toa -= WEEK_S;
        } else if since_toa < -WEEK_S / 2.0 {
            since_toa += WEEK_S;
        }
        let m0 = quantize_angle(entry.mean_anomaly + n0 * since_toa, -31, 32);
        // Ω(t) = Ω0 + (Ω̇ − Ω̇e)(t − t_oa) − Ω̇e t_oa (truth) = Ω0' + (Ω̇ − Ω̇e)(t − t_oe) − Ω̇e t_oe
        let omega0 = entry.omega0 + (entry.omega_dot - OMEGA_EARTH) * since_toa
            - OMEGA_EARTH * entry.toa_s
            + OMEGA_EARTH * toe_s;
        let (af0, af1) = self.clock_poly(entry, tau_toe);
        let iodc = (issue.rem_euclid(1024.0)) as u16;
        let raw = Quantized {
            sqrt_a,
            e: quantize_unsigned(entry.eccentricity, -33, 32),
            i0: quantize_angle(entry.inclination, -31, 32),
            omega0: quantize_angle(omega0, -31, 32),
            omega: quantize_angle(entry.argument_of_perigee, -31, 32),
            m0,
            delta_n,
            omega_dot: quantize_signed(entry.omega_dot / GPS_PI, -43, 24),
            af0: quantize_signed(af0, -31, 22),
            af1: quantize_signed(af1, -43, 16),
            tgd: quantize_signed(self.tgd_s(prn), -31, 8),
            toe: quantize_unsigned(toe_s, 4, 16),
        };
        Some(BroadcastEphemeris {
            prn,
            week: toe_week,
            toe_s: f64::from(raw.toe) * 16.0,
            toc_s: f64::from(raw.toe) * 16.0,
            iode: (iodc & 0xFF) as u8,
            iodc,
            health: entry.health.min(63) as u8,
            sqrt_a: f64::from(raw.sqrt_a) * pow2(-19),
            e: f64::from(raw.e) * pow2(-33),
            i0: angle_of(raw.i0, -31),
            omega0: angle_of(raw.omega0, -31),
            omega: angle_of(raw.omega, -31),
            m0: angle_of(raw.m0, -31),
            delta_n: angle_of(raw.delta_n, -43),
            omega_dot: angle_of(raw.omega_dot, -43),
            af0: f64::from(raw.af0) * pow2(-31),
            af1: f64::from(raw.af1) * pow2(-43),
            tgd: f64::from(raw.tgd) * pow2(-31),
            raw,
        })
    }

    /// `Δt_sv` of the satellite's L1 C/A signal at GPS time (`week`, `tow_s`), s: the truth's
    /// clock polynomial, the relativistic term of the truth's orbit and `−T_GD`. The signal
    /// transmitted at GPS time `t` carries the signal time `t + Δt_sv(t)`.
    pub fn signal_clock_offset_s(&self, prn: u8, week: u16, tow_s: f64) -> Option<f64> {
        let entry = self.entry(prn)?;
        let tau = self.tau(week, tow_s);
        let (bias, _) = self.clock_poly(entry, tau);
        let ecc = eccentric_anomaly(entry, tau);
        let relativistic = F_RELATIVISTIC * entry.eccentricity * entry.sqrt_a * ecc.sin();
        let tgd = f64::from(quantize_signed(self.tgd_s(prn), -31, 8)) * pow2(-31);
        Some(bias + relativistic - tgd)
    }

    /// The ten 24-bit data words of the subframe of `prn` that starts at (`week`,
    /// `start_tow_s`) (a multiple of 6 s), word 1 first; the HOW and word 10 with their
    /// parity-solving bits still zero. `None` for a PRN the almanac lacks.
    pub fn subframe_words(&self, prn: u8, week: u16, start_tow_s: u32) -> Option<[u32; 10]> {
        let index = start_tow_s / 6;
        let id = index % 5 + 1;
        let frame_start = f64::from(start_tow_s - 6 * (id - 1));
        let eph = self.ephemeris(prn, week, frame_start)?;
        let mut w = [0u32; 10];
        w[0] = PREAMBLE << 16;
        let next = (index + 1) % 100_800;
        w[1] = (next << 7) | (id << 2);
        let page = (start_tow_s / 30) % 25;
        match id {
            1 => self.subframe1(&eph, &mut w),
            2 => subframe2(&eph, &mut w),
            3 => subframe3(&eph, &mut w),
            4 => self.subframe4(page as usize, week, &mut w),
            _ => self.subframe5(page as usize, week, &mut w),
        }
        Some(w)
    }

    fn subframe1(&self, e: &BroadcastEphemeris, w: &mut [u32; 10]) {
        let q = &e.raw;
        let wn = u32::from(e.week % 1024);
        let ura = 0u32;
        w[2] = (wn << 14)
            | (0b01 << 12)
            | (ura << 8)
            | (u32::from(e.health) << 2)
            | (u32::from(e.iodc) >> 8);
        w[6] = bits(q.tgd, 8);
        w[7] = ((u32::from(e.iodc) & 0xFF) << 16) | q.toe;
        w[8] = bits(q.af1, 16);
        w[9] = bits(q.af0, 22) << 2;
    }

    fn subframe4(&self, page: usize, week: u16, w: &mut [u32; 10]) {
        let sv_id = SUBFRAME4_SV_IDS[page];
        match sv_id {
            25..=32 => self.almanac_page(sv_id, week, w),
            56 => self.page18(week, w),
            63 => {
                w[2] = (0b01 << 22) | (63 << 16);
                // A-S flags and health of SV 25–32: healthy, A-S on (1001)
                for x in w.iter_mut().take(8).skip(3) {
                    *x = 0x99_9999;
                }
            }
            _ => reserved_page(sv_id, w),
        }
    }

    fn subframe5(&self, page: usize, week: u16, w: &mut [u32; 10]) {
        if page < 24 {
            self.almanac_page(page as u8 + 1, week, w);
            return;
        }
        // page 25: t_oa, WN_a and the health of SV 1–24
        let toa = (self.almanac.reference_time_s() / 4096.0).round() as u32;
        let wna = u32::from(self.almanac_week % 256);
        w[2] = (0b01 << 22) | (51 << 16) | ((toa & 0xFF) << 8) | wna;
        for sv in 1..=24u8 {
            let h = match self.entry(sv) {
                Some(e) => e.health.min(63),
                None => 0b11_1111,
            };
            let k = usize::from(sv - 1);
            let word = 3 + k / 4;
            let shift = 18 - 6 * (k % 4) as u32;
            w[word] |= h << shift;
        }
    }

    /// An almanac page for `prn`; a dummy page (SV ID 0, alternating bits) when the almanac
    /// has no such satellite.
    fn almanac_page(&self, prn: u8, _week: u16, w: &mut [u32; 10]) {
        let Some(a) = self.entry(prn) else {
            w[2] = (0b01 << 22) | 0xAAAA;
            for x in w.iter_mut().skip(3) {
                *x = 0xAA_AAAA;
            }
            w[9] &= !0b11;
            return;
        };
        let e = quantize_unsigned(a.eccentricity, -21, 16);
        let toa = quantize_unsigned(a.toa_s, 12, 8);
        let di = quantize_signed(a.inclination / GPS_PI - 0.30, -19, 16);
        let odot = quantize_signed(a.omega_dot / GPS_PI, -38, 16);
        let health = a.health.min(255);
        let sqa = quantize_unsigned(a.sqrt_a, -11, 24);
        let om0 = quantize_angle(a.omega0, -23, 24);
        let arg = quantize_angle(a.argument_of_perigee, -23, 24);
        let m0 = quantize_angle(a.mean_anomaly, -23, 24);
        let af0 = bits(quantize_signed(a.af0, -20, 11), 11);
        let af1 = bits(quantize_signed(a.af1, -38, 11), 11);
        w[2] = (0b01 << 22) | (u32::from(prn) << 16) | e;
        w[3] = (toa << 16) | bits(di, 16);
        w[4] = (bits(odot, 16) << 8) | health;
        w[5] = sqa;
        w[6] = bits(om0, 24);
        w[7] = bits(arg, 24);
        w[8] = bits(m0, 24);
        w[9] = ((af0 >> 3) << 16) | (af1 << 5) | ((af0 & 0b111) << 2);
    }

    fn page18(&self, week: u16, w: &mut [u32; 10]) {
        let p = &self.iono_utc;
        let s8 = |x: f64, scale: i32| bits(quantize_signed(x, scale, 8), 8);
        w[2] = (0b01 << 22) | (56 << 16) | (s8(p.alpha[0], -30) << 8) | s8(p.alpha[1], -27);
        w[3] = (s8(p.alpha[2], -24) << 16) | (s8(p.alpha[3], -24) << 8) | s8(p.beta[0], 11);
        w[4] = (s8(p.beta[1], 14) << 16) | (s8(p.beta[2], 16) << 8) | s8(p.beta[3], 16);
        w[5] = bits(quantize_signed(p.a1, -50, 24), 24);
        let a0 = quantize_signed(p.a0_s, -30, 32) as u32;
        w[6] = a0 >> 8;
        let wnt = u32::from(week % 256);
        w[7] = ((a0 & 0xFF) << 16) | ((p.tot_s >> 12) << 8) | wnt;
        w[8] = (bits(i32::from(p.delta_t_ls_s), 8) << 16) | (wnt << 8) | u32::from(p.day_number);
        w[9] = bits(i32::from(p.delta_t_lsf_s), 8) << 16;
    }

    /// The 300 transmitted bits of a subframe (parity encoded; the stream of every subframe
    /// starts after a word ending in `00`), first bit first.
    pub fn subframe_bits(&self, prn: u8, week: u16, start_tow_s: u32) -> Option<[bool; 300]> {
        let words = self.subframe_words(prn, week, start_tow_s)?;
        Some(encode_subframe(&words))
    }

    /// The data bit (`true` = 1) that satellite `prn` transmits at signal time (`week`,
    /// `tow_s`) (the satellite's clock: GPS time plus [`Self::signal_clock_offset_s`]).
    pub fn data_bit(&self, prn: u8, week: u16, tow_s: f64) -> Option<bool> {
        let (week, tow) = normalize(week, tow_s);
        let start = ((tow / SUBFRAME_S).floor() * SUBFRAME_S) as u32;
        let bit = (((tow - f64::from(start)) / BIT_S).floor() as usize).min(299);
        self.subframe_bits(prn, week, start).map(|b| b[bit])
    }

    /// The data bit at GPS time (`week`, `tow_s`): the bit of signal time `t + Δt_sv(t)`.
    pub fn data_bit_at_gps_time(&self, prn: u8, week: u16, tow_s: f64) -> Option<bool> {
        let offset = self.signal_clock_offset_s(prn, week, tow_s)?;
        self.data_bit(prn, week, tow_s + offset)
    }
}

/// A cache of one subframe per PRN for bit-by-bit use.
#[derive(Clone, Debug, Default)]
pub struct LnavBitStream {
    cache: Vec<(u8, u16, u32, [bool; 300])>,
}

impl LnavBitStream {
    /// The bit of `prn` at signal time (`week`, `tow_s`), encoding each subframe once.
    pub fn bit(&mut self, encoder: &LnavEncoder, prn: u8, week: u16, tow_s: f64) -> Option<bool> {
        let (week, tow) = normalize(week, tow_s);
        let start = ((tow / SUBFRAME_S).floor() * SUBFRAME_S) as u32;
        let bit = (((tow - f64::from(start)) / BIT_S).floor() as usize).min(299);
        if let Some(c) = self
            .cache
            .iter()
            .find(|c| c.0 == prn && c.1 == week && c.2 == start)
        {
            return Some(c.3[bit]);
        }
        let bits = encoder.subframe_bits(prn, week, start)?;
        self.cache.retain(|c| c.0 != prn);
        self.cache.push((prn, week, start, bits));
        Some(bits[bit])
    }
}

fn normalize(week: u16, tow_s: f64) -> (u16, f64) {
    let weeks = (tow_s / WEEK_S).floor();
    ((f64::from(week) + weeks) as u16, tow_s - weeks * WEEK_S)
}

fn subframe2(e: &BroadcastEphemeris, w: &mut [u32; 10]) {
    let q = &e.raw;
    let m0 = q.m0 as u32;
    w[2] = (u32::from(e.iode) << 16) | bits(0, 16);
    w[3] = (bits(q.delta_n, 16) << 8) | (m0 >> 24);
    w[4] = m0 & 0xFF_FFFF;
    w[5] = q.e >> 24;
    w[6] = q.e & 0xFF_FFFF;
    w[7] = q.sqrt_a >> 24;
    w[8] = q.sqrt_a & 0xFF_FFFF;
    w[9] = q.toe << 8;
}

fn subframe3(e: &BroadcastEphemeris, w: &mut [u32; 10]) {
    let q = &e.raw;
    let (om0, i0, om) = (q.omega0 as u32, q.i0 as u32, q.omega as u32);
    w[2] = om0 >> 24;
    w[3] = om0 & 0xFF_FFFF;
    w[4] = i0 >> 24;
    w[5] = i0 & 0xFF_FFFF;
    w[6] = om >> 24;
    w[7] = om & 0xFF_FFFF;
    w[8] = bits(q.omega_dot, 24);
    w[9] = u32::from(e.iode) << 16;
}

/// A reserved page: its SV ID and alternating ones and zeros.
fn reserved_page(sv_id: u8, w: &mut [u32; 10]) {
    w[2] = (0b01 << 22) | (u32::from(sv_id) << 16) | 0xAAAA;
    for x in w.iter_mut().skip(3) {
        *x = 0xAA_AAAA;
    }
}

/// The low `n` bits of a two's-complement value.
fn bits(v: i32, n: u32) -> u32 {
    (v as u32) & ((1u64 << n) - 1) as u32
}

/// Eccentric anomaly of the truth's almanac orbit at `tau` (as the truth computes it).
fn eccentric_anomaly(entry: &AlmanacEntry, tau: f64) -> f64 {
    let a = entry.sqrt_a * entry.sqrt_a;
    let n0 = (MU / (a * a * a)).sqrt();
    let mut tk = tau - entry.toa_s;
    if tk > WEEK_S / 2.0 {
        tk -= WEEK_S;
    } else if tk < -WEEK_S / 2.0 {
        tk += WEEK_S;
    }
    let m = entry.mean_anomaly + n0 * tk;
    let mut ea = m;
    for _ in 0..30 {
        let step = (ea - entry.eccentricity * ea.sin() - m) / (1.0 - entry.eccentricity * ea.cos());
        ea -= step;
        if step.abs() < 1e-15 {
            break;
        }
    }
    ea
}

// ---- parity (IS-GPS-200 Table 20-XIV), written out bit by bit ---------------------------

/// For `D25 … D30`: the previous word's bit (29 or 30) and the data bits `d1 … d24`.
const PARITY_TABLE: [(u8, &[u8]); 6] = [
    (29, &[1, 2, 3, 5, 6, 10, 11, 12, 13, 14, 17, 18, 20, 23]),
    (30, &[2, 3, 4, 6, 7, 11, 12, 13, 14, 15, 18, 19, 21, 24]),
    (29, &[1, 3, 4, 5, 7, 8, 12, 13, 14, 15, 16, 19, 20, 22]),
    (30, &[2, 4, 5, 6, 8, 9, 13, 14, 15, 16, 17, 20, 21, 23]),
    (30, &[1, 3, 5, 6, 7, 9, 10, 14, 15, 16, 17, 18, 21, 22, 24]),
    (29, &[3, 5, 6, 8, 9, 10, 11, 13, 15, 19, 22, 23, 24]),
];

/// Transmitted 30 bits of a word with source data `d[0..24]` after a word ending in
/// `(d29, d30)`.
pub fn encode_word_bits(d: &[bool; 24], d29: bool, d30: bool) -> [bool; 30] {
    let mut out = [false; 30];
    for (o, &di) in out.iter_mut().zip(d.iter()) {
        *o = di ^ d30;
    }
    for (k, (star, terms)) in PARITY_TABLE.iter().enumerate() {
        let mut p = if *star == 29 { d29 } else { d30 };
        for &t in terms.iter() {
            p ^= d[usize::from(t) - 1];
        }
        out[24 + k] = p;
    }
    out
}

fn word_bits(data: u32) -> [bool; 24] {
    let mut d = [false; 24];
    for (i, b) in d.iter_mut().enumerate() {
        *b = (data >> (23 - i)) & 1 == 1;
    }
    d
}

/// Encodes ten data words into 300 bits; the HOW's and word 10's bits 23–24 are chosen so
/// that their `D29`, `D30` are zero.
pub fn encode_subframe(words: &[u32; 10]) -> [bool; 300] {
    let mut out = [false; 300];
    let (mut d29, mut d30) = (false, false);
    for (w, &data) in words.iter().enumerate() {
        let mut d = word_bits(data);
        let mut t = encode_word_bits(&d, d29, d30);
        if w == 1 || w == 9 {
            'solve: for combo in 0..4u8 {
                d[22] = combo & 0b10 != 0;
                d[23] = combo & 0b01 != 0;
                t = encode_word_bits(&d, d29, d30);
                if !t[28] && !t[29] {
                    break 'solve;
                }
            }
        }
        out[30 * w..30 * w + 30].copy_from_slice(&t);
        d29 = t[28];
        d30 = t[29];
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use gnss_attitude::nav::bits::BitSyncConfig;
    use gnss_attitude::nav::message::{decode, NavMessage};
    use gnss_attitude::nav::parity::decode_word;
    use gnss_attitude::nav::store::StoreUpdate;
    use gnss_attitude::nav::{ChannelDecoder, Ephemeris, GpsTime, NavigationStore};
    use nalgebra::Vector3;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, StandardNormal};

    fn to_u32(bits: &[bool]) -> u32 {
        bits.iter().fold(0, |acc, &b| (acc << 1) | u32::from(b))
    }

    #[test]
    fn the_encoders_parity_passes_the_cores_check_and_hand_examples() {
        // d1 alone after 00: D25, D27, D29 set
        let mut d = [false; 24];
        d[0] = true;
        let t = encode_word_bits(&d, false, false);
        assert_eq!(to_u32(&t[24..]), 0b10_1010);
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for _ in 0..500 {
            let data: u32 = rng.random::<u32>() & 0xFF_FFFF;
            for (a, b) in [(false, false), (false, true), (true, false), (true, true)] {
                let t = encode_word_bits(&word_bits(data), a, b);
                assert_eq!(decode_word(to_u32(&t), a, b), Ok(data));
            }
        }
    }

    fn to_ephemeris(b: &BroadcastEphemeris) -> Ephemeris {
        Ephemeris {
            prn: b.prn,
            week: b.week,
            toe_s: b.toe_s,
            toc_s: b.toc_s,
            iode: b.iode,
            iodc: b.iodc,
            health: b.health,
            ura_index: 0,
            fit_interval: false,
            sqrt_a: b.sqrt_a,
            e: b.e,
            i0: b.i0,
            omega0: b.omega0,
            omega: b.omega,
            m0: b.m0,
            delta_n: b.delta_n,
            idot: 0.0,
            omega_dot: b.omega_dot,
            cuc: 0.0,
            cus: 0.0,
            crc: 0.0,
            crs: 0.0,
            cic: 0.0,
            cis: 0.0,
            af0: b.af0,
            af1: b.af1,
            af2: 0.0,
            tgd: b.tgd,
        }
    }

    /// Feeds `seconds` of prompts of `prn` from GPS time (`week`, `tow0`) into a channel
    /// decoder (1 ms epochs at 40 dB-Hz, the polarity inverted when `invert`) and the store.
    fn decode_stream(
        enc: &LnavEncoder,
        prn: u8,
        tow0: f64,
        seconds: f64,
        invert: bool,
        store: &mut NavigationStore,
        rng: &mut ChaCha8Rng,
    ) -> ChannelDecoder {
        let mut dec = ChannelDecoder::new(prn, BitSyncConfig::default());
        let mut stream = LnavBitStream::default();
        let amplitude = (2.0f64 * 10f64.powf(4.0) * 1e-3).sqrt();
        let epochs = (seconds * 1000.0) as u64;
        for k in 0..epochs {
            let tow = tow0 + k as f64 * 1e-3 + 0.0005;
            let bit = stream.bit(enc, prn, BUNDLED_ALMANAC_WEEK, tow).unwrap();
            let s = if bit ^ invert { amplitude } else { -amplitude };
            let n: f64 = StandardNormal.sample(rng);
            match dec.push_prompt(k, (s + n) as f32) {
                Ok(Some(sf)) => {
                    if let Err(e) = store.add_subframe(prn, &sf) {
                        panic!("store refused prn {prn}: {e}");
                    }
                    if let Some(w) = store.week() {
                        dec.set_week(w);
                    }
                }
                Ok(None) => {}
                Err(e) => panic!("decode error prn {prn} at {k}: {e}"),
            }
        }
        dec
    }

    #[test]
    fn encoder_to_core_decoder_round_trip_of_all_subframes() {
        let enc = LnavEncoder::bundled();
        let mut store = NavigationStore::default();
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let tow0 = 233_472.0 + 1000.0 + 0.123; // an arbitrary start inside a subframe
                                               // one satellite through a whole 25-page cycle (12.5 min), inverted polarity
        let dec = decode_stream(&enc, 5, tow0, 760.0, true, &mut store, &mut rng);
        assert_eq!(dec.parity_failures(), 0);
        assert!(dec.subframe_synchronized());
        // the anchor: a subframe start on the epoch count, with its time of week
        let anchor = dec.anchor().unwrap();
        let anchor_tow = tow0 + anchor.start_epoch as f64 * 1e-3 + 0.0005;
        assert!(
            (anchor_tow - f64::from(anchor.tow_s)).abs() < 1e-3,
            "{anchor_tow} vs {}",
            anchor.tow_s
        );
        assert_eq!(anchor.week, Some(BUNDLED_ALMANAC_WEEK));
        // the ephemeris equals what was encoded
        let decoded = *store.ephemeris(5).unwrap();
        let sent = enc
            .ephemeris(5, BUNDLED_ALMANAC_WEEK, f64::from(anchor.tow_s) - 1.0)
            .unwrap();
        assert_eq!(decoded, to_ephemeris(&sent));
        // every almanac page of the YUMA file, within the almanac's scale factors
        for a in &enc.almanac.entries {
            let d = store
                .almanac(a.prn)
                .unwrap_or_else(|| panic!("almanac of prn {}", a.prn));
            assert!((d.sqrt_a - a.sqrt_a).abs() <= pow2(-12) * 1.01);
            assert!((d.e - a.eccentricity).abs() <= pow2(-22) * 1.01);
            assert!((d.af1 - a.af1).abs() <= pow2(-39) * 1.01);
            assert!((d.af0 - a.af0).abs() <= pow2(-21) * 1.01);
            assert!((d.toa_s - a.toa_s).abs() < 1e-9);
            assert!((d.i0 - a.inclination).abs() <= GPS_PI * pow2(-20) * 1.01);
            assert_eq!(u32::from(d.health), a.health.min(255));
        }
        assert!(store.almanac(28).is_none(), "PRN 28 is a dummy page");
        let r = store.almanac_reference().unwrap();
        assert_eq!(
            (r.toa_s, r.week_mod_256),
            (233_472, (BUNDLED_ALMANAC_WEEK % 256) as u8)
        );
        assert_eq!(r.health[10], 63);
        let iono = store.ionosphere().unwrap();
        for k in 0..4 {
            assert!(
                (f64::from(iono.alpha[k]) - enc.iono_utc.alpha[k]).abs()
                    <= enc.iono_utc.alpha[k].abs() * 0.01 + 1e-12
            );
            assert!((f64::from(iono.beta[k]) - enc.iono_utc.beta[k]).abs() <= 2048.0);
        }
        let utc = store.utc().unwrap();
        assert_eq!(utc.delta_t_ls_s, 18);
        assert!((utc.a0_s - enc.iono_utc.a0_s).abs() < pow2(-30));
        assert_eq!(store.counters().parity_failures, 0);
        // other satellites, normal polarity, 45 s from another start: ephemerides complete
        for prn in [1u8, 12, 24, 31] {
            let tow = 233_472.0 + 5000.0 + 2.5 * f64::from(prn);
            let dec = decode_stream(&enc, prn, tow, 45.0, false, &mut store, &mut rng);
            assert_eq!(dec.parity_failures(), 0);
            let sent = enc
                .ephemeris(prn, BUNDLED_ALMANAC_WEEK, tow + 30.0)
                .unwrap();
            assert_eq!(
                store.ephemeris(prn).copied(),
                Some(to_ephemeris(&sent)),
                "prn {prn}"
            );
        }
        // PRN 11 is unhealthy: its ephemeris is refused
        let mut sick = NavigationStore::default();
        let words: Vec<[u32; 10]> = (0..3)
            .map(|k| {
                enc.subframe_words(11, BUNDLED_ALMANAC_WEEK, 240_000 + 6 * k)
                    .unwrap()
            })
            .collect();
        let mut results = Vec::new();
        for w in &words {
            let bits = encode_subframe(w);
            let mut data = [0u32; 10];
            let (mut d29, mut d30) = (false, false);
            for (i, d) in data.iter_mut().enumerate() {
                let word = &bits[30 * i..30 * i + 30];
                *d = decode_word(to_u32(word), d29, d30).unwrap();
                (d29, d30) = (word[28], word[29]);
            }
            let sf = gnss_attitude::nav::Subframe {
                words: data,
                start_epoch: 0,
                inverted: false,
            };
            assert!(matches!(
                decode(&sf),
                NavMessage::Clock(_) | NavMessage::Orbit2(_) | NavMessage::Orbit3(_)
            ));
            results.push(sick.add_subframe(11, &sf));
        }
        assert!(
            results[2].is_err() && sick.counters().implausible == 1,
            "{results:?}"
        );
        assert!(matches!(results[0], Ok(StoreUpdate::Pending)));
    }

    #[test]
    fn decoded_satellite_positions_match_the_truth_over_an_hour() {
        let enc = LnavEncoder::bundled();
        let t0 = enc.almanac.reference_time_s() + 3.0 * 3600.0;
        let mut worst = (0.0f64, 0u8);
        let mut worst_clock = 0.0f64;
        for a in enc.almanac.entries.iter().filter(|a| a.health == 0) {
            for k in 0..=60 {
                let tow = t0 + 60.0 * f64::from(k);
                let b = enc.ephemeris(a.prn, BUNDLED_ALMANAC_WEEK, tow).unwrap();
                let eph = to_ephemeris(&b);
                let t = GpsTime::new(BUNDLED_ALMANAC_WEEK, tow).unwrap();
                let s = eph.satellite_state(&t).unwrap();
                let (p, v) = a.position_velocity(tow);
                let d = (Vector3::from(s.position_m) - p).norm();
                if d > worst.0 {
                    worst = (d, a.prn);
                }
                assert!((Vector3::from(s.velocity_m_s) - v).norm() < 1e-4);
                // the receiver's clock correction at the signal time vs the signal's offset
                let offset = enc
                    .signal_clock_offset_s(a.prn, BUNDLED_ALMANAC_WEEK, tow)
                    .unwrap();
                let t_sv = t.add_seconds(offset).unwrap();
                let (t_back, _) = eph.state_at_transmission(&t_sv).unwrap();
                worst_clock = worst_clock.max(t_back.seconds_since(&t).abs());
            }
        }
        println!(
            "decoded ephemeris vs truth over 1 h (two issues), 30 satellites: worst {:.4} m (PRN {}), clock {:.3e} s",
            worst.0, worst.1, worst_clock
        );
        assert!(worst.0 < 0.1, "{worst:?}");
        assert!(worst_clock < 1e-9, "{worst_clock}");
    }

    #[test]
    fn data_bits_follow_the_signal_clock_and_the_how_counts_subframes() {
        let enc = LnavEncoder::bundled();
        let week = BUNDLED_ALMANAC_WEEK;
        // the preamble at every subframe start, the HOW counting
        for k in 0..10u32 {
            let start = 240_000 + 6 * k;
            let words = enc.subframe_words(3, week, start).unwrap();
            assert_eq!(words[0] >> 16, PREAMBLE);
            assert_eq!(words[1] >> 7, start / 6 + 1);
            assert_eq!((words[1] >> 2) & 7, (start / 6) % 5 + 1);
            let bits = enc.subframe_bits(3, week, start).unwrap();
            assert_eq!(to_u32(&bits[..8]), PREAMBLE);
            assert!(!bits[298] && !bits[299]);
            assert!(!bits[58] && !bits[59]);
            assert_eq!(
                enc.data_bit(3, week, f64::from(start) + 0.0199),
                Some(bits[0])
            );
            assert_eq!(
                enc.data_bit(3, week, f64::from(start) + 5.99),
                Some(bits[299])
            );
        }
        // the week's last subframe counts the next week's start (TOW count 0)
        let words = enc.subframe_words(3, week, 604_794).unwrap();
        assert_eq!(words[1] >> 7, 0);
        let offset = enc.signal_clock_offset_s(3, week, 240_000.0).unwrap();
        assert_eq!(
            enc.data_bit_at_gps_time(3, week, 240_000.01 - offset),
            enc.data_bit(3, week, 240_000.01)
        );
        assert!(enc.data_bit(28, week, 240_000.0).is_none());
    }
}
