//! A deterministic navigation example without allocation: a 24-satellite constellation, the
//! words of its subframes 1–3 (a small encoder with the crate's own parity), and noise-free
//! pseudoranges and Dopplers of a receiver. The firmware budgets and the tests use it.

use heapless::Vec;
use nalgebra::Vector3;

use super::atmosphere::{klobuchar_delay_m, troposphere_delay_m};
use super::ephemeris::{Ephemeris, OrbitError};
use super::geodesy::{elevation_azimuth, Geodetic};
use super::message::KlobucharParameters;
use super::parity::{encode_word, solve_trailing_zeros};
use super::solution::{Observation, MAX_SATELLITES};
use super::subframe::PREAMBLE;
use super::time::{GpsTime, TimeError};
use super::{GPS_PI, L1_WAVELENGTH_M, OMEGA_EARTH, SPEED_OF_LIGHT};

/// A typical broadcast ionosphere (mid solar activity).
pub const EXAMPLE_KLOBUCHAR: KlobucharParameters = KlobucharParameters {
    alpha: [1.1176e-8, 7.4506e-9, -5.9605e-8, -5.9605e-8],
    beta: [90_112.0, 16_384.0, -196_608.0, -131_072.0],
};

/// Week of the example's ephemerides.
pub const EXAMPLE_WEEK: u16 = 2195;
/// Reference time of the example's ephemerides, s of the week.
pub const EXAMPLE_TOE_S: f64 = 237_600.0;
/// A line of sight passing closer than this to the Earth's centre is hidden, m.
const OCCULTATION_RADIUS_M: f64 = 6_478_137.0;
/// Satellites of the example constellation.
pub const EXAMPLE_SATELLITES: usize = 24;

/// A value from a small deterministic hash of `k`, uniform in `[lo, hi)`.
fn spread(k: u32, salt: u32, lo: f64, hi: f64) -> f64 {
    let mut x = k.wrapping_mul(0x9E37_79B9) ^ salt.wrapping_mul(0x85EB_CA6B);
    x ^= x >> 15;
    x = x.wrapping_mul(0x2C1B_3C6D);
    x ^= x >> 12;
    lo + (hi - lo) * f64::from(x) / 4_294_967_296.0
}

/// The example constellation: six planes of four plausible GPS satellites with harmonic
/// corrections and clocks.
pub fn constellation() -> [Ephemeris; EXAMPLE_SATELLITES] {
    core::array::from_fn(|i| {
        let k = i as u32;
        let plane = f64::from(k % 6);
        Ephemeris {
            prn: (i + 1) as u8,
            week: EXAMPLE_WEEK,
            toe_s: EXAMPLE_TOE_S,
            toc_s: EXAMPLE_TOE_S,
            iode: (20 + i) as u8,
            iodc: (20 + i) as u16,
            health: 0,
            ura_index: 0,
            fit_interval: false,
            sqrt_a: spread(k, 1, 5153.2, 5154.0),
            e: spread(k, 2, 0.001, 0.02),
            i0: spread(k, 3, 0.94, 0.98),
            omega0: (plane * 60.0 - 180.0 + spread(k, 4, -2.0, 2.0)) * GPS_PI / 180.0,
            omega: spread(k, 5, -3.1, 3.1),
            m0: (f64::from(k / 6) * 90.0 + plane * 15.0 - 172.0) * GPS_PI / 180.0,
            delta_n: spread(k, 6, 3e-9, 5e-9),
            idot: spread(k, 7, -5e-10, 5e-10),
            omega_dot: spread(k, 8, -8.5e-9, -7.5e-9),
            cuc: spread(k, 9, -5e-6, 5e-6),
            cus: spread(k, 10, -1e-5, 1e-5),
            crc: spread(k, 11, -300.0, 300.0),
            crs: spread(k, 12, -120.0, 120.0),
            cic: spread(k, 13, -1e-7, 1e-7),
            cis: spread(k, 14, -1e-7, 1e-7),
            af0: spread(k, 15, -5e-4, 5e-4),
            af1: spread(k, 16, -1e-11, 1e-11),
            af2: 0.0,
            tgd: spread(k, 17, -1e-8, 1e-8),
        }
    })
}

/// `x / 2^scale` rounded, as the low `bits` of its two's complement.
fn q(x: f64, scale: i32, bits: u32) -> u32 {
    let v = libm::round(x / libm::ldexp(1.0, scale)) as i64;
    (v as u64 & ((1u64 << bits) - 1)) as u32
}

/// An angle in radians as semicircles quantized at `2^scale`.
fn qa(x: f64, scale: i32, bits: u32) -> u32 {
    q(x / GPS_PI, scale, bits)
}

/// The ten data words (24 bits each) of subframe `id` (1–3) of `e`, with the HOW counting
/// `tow_count` (the next subframe's start / 6 s). Subframes 4 and 5 come out as a TLM and a
/// HOW over empty words.
pub fn subframe_words(e: &Ephemeris, id: u8, tow_count: u32) -> [u32; 10] {
    let mut w = [0u32; 10];
    w[0] = PREAMBLE << 16;
    w[1] = ((tow_count & 0x1_FFFF) << 7) | (u32::from(id & 7) << 2);
    let iodc = u32::from(e.iodc & 0x3FF);
    let iode = u32::from(e.iode);
    match id {
        1 => {
            w[2] = (u32::from(e.week % 1024) << 14)
                | (u32::from(e.ura_index & 0xF) << 8)
                | (u32::from(e.health & 0x3F) << 2)
                | (iodc >> 8);
            w[6] = q(e.tgd, -31, 8);
            w[7] = ((iodc & 0xFF) << 16) | q(e.toc_s, 4, 16);
            w[8] = (q(e.af2, -55, 8) << 16) | q(e.af1, -43, 16);
            w[9] = q(e.af0, -31, 22) << 2;
        }
        2 => {
            let (m0, ecc, sqa) = (qa(e.m0, -31, 32), q(e.e, -33, 32), q(e.sqrt_a, -19, 32));
            w[2] = (iode << 16) | q(e.crs, -5, 16);
            w[3] = (qa(e.delta_n, -43, 16) << 8) | (m0 >> 24);
            w[4] = m0 & 0xFF_FFFF;
            w[5] = (q(e.cuc, -29, 16) << 8) | (ecc >> 24);
            w[6] = ecc & 0xFF_FFFF;
            w[7] = (q(e.cus, -29, 16) << 8) | (sqa >> 24);
            w[8] = sqa & 0xFF_FFFF;
            w[9] = q(e.toe_s, 4, 16) << 8;
        }
        3 => {
            let (om0, i0, om) = (
                qa(e.omega0, -31, 32),
                qa(e.i0, -31, 32),
                qa(e.omega, -31, 32),
            );
            w[2] = (q(e.cic, -29, 16) << 8) | (om0 >> 24);
            w[3] = om0 & 0xFF_FFFF;
            w[4] = (q(e.cis, -29, 16) << 8) | (i0 >> 24);
            w[5] = i0 & 0xFF_FFFF;
            w[6] = (q(e.crc, -5, 16) << 8) | (om >> 24);
            w[7] = om & 0xFF_FFFF;
            w[8] = qa(e.omega_dot, -43, 24);
            w[9] = (iode << 16) | (qa(e.idot, -43, 14) << 2);
        }
        _ => {}
    }
    w
}

/// The 300 transmitted bits of ten data words after a word ending in `00`, first bit first,
/// with the HOW's and word 10's last bits solved to `00`.
pub fn subframe_bits(words: &[u32; 10]) -> [bool; 300] {
    let mut out = [false; 300];
    let (mut d29, mut d30) = (false, false);
    for (w, (&data, bits)) in words.iter().zip(out.chunks_exact_mut(30)).enumerate() {
        let data = if w == 1 || w == 9 {
            solve_trailing_zeros(data, d29, d30)
        } else {
            data
        };
        let word = encode_word(data, d29, d30);
        for (i, b) in bits.iter_mut().enumerate() {
            *b = (word >> (29 - i)) & 1 == 1;
        }
        d29 = (word >> 1) & 1 == 1;
        d30 = word & 1 == 1;
    }
    out
}

/// Error returned by [`observations`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ExampleError {
    /// A satellite's orbit.
    #[error("orbit")]
    Orbit(#[from] OrbitError),
    /// A time out of range.
    #[error("time")]
    Time(#[from] TimeError),
}

impl crate::error::Error for ExampleError {
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            Self::Orbit(e) => crate::error::Error::kind(e),
            Self::Time(e) => crate::error::Error::kind(e),
        }
    }
}

/// Noise-free pseudoranges and Dopplers of the satellites of `ephemerides` that clear the
/// Earth (their line of sight passes 100 km above the surface) for a receiver at `position`
/// (ECEF, m) with velocity `velocity` (ECEF, m/s) and clock bias `clock_bias_m`, received at
/// GPS time `receive`; at most `count` (and [`MAX_SATELLITES`]), highest above the
/// receiver's horizontal plane first. With `atmosphere`, the broadcast ionosphere and the
/// troposphere of [`super::atmosphere`] are added (a ground receiver).
///
/// # Errors
/// [`ExampleError`] from a satellite's orbit or the time.
pub fn observations(
    ephemerides: &[Ephemeris],
    position: &[f64; 3],
    velocity: &[f64; 3],
    clock_bias_m: f64,
    receive: &GpsTime,
    count: usize,
    atmosphere: Option<&KlobucharParameters>,
) -> Result<Vec<Observation, MAX_SATELLITES>, ExampleError> {
    let mut ranked: Vec<(f64, Observation), EXAMPLE_SATELLITES> = Vec::new();
    let site = Geodetic::from_ecef(position);
    for e in ephemerides {
        let Some((height, mut obs, u)) = observe(e, position, velocity, clock_bias_m, receive)?
        else {
            continue;
        };
        if let (Some(params), Some(g)) = (atmosphere, site) {
            let ned = g.ecef_to_ned() * Vector3::new(u[0] as f32, u[1] as f32, u[2] as f32);
            let (el, az) = elevation_azimuth(&ned);
            let (lat, lon) = (g.lat_rad as f32, g.lon_rad as f32);
            let delay = klobuchar_delay_m(params, lat, lon, el.max(0.0), az, receive.tow_s)
                + troposphere_delay_m(g.height_m as f32, el.max(0.0));
            obs.pseudorange_m += f64::from(delay);
        }
        if ranked.push((height, obs)).is_err() {
            break;
        }
    }
    ranked.sort_unstable_by(|a, b| b.0.total_cmp(&a.0));
    let mut out = Vec::new();
    for (_, o) in ranked.iter().take(count) {
        if out.push(*o).is_err() {
            break;
        }
    }
    Ok(out)
}

/// One satellite: `(sine of the elevation above the horizontal plane, observation, unit line
/// of sight ECEF)`, `None` when the Earth hides it.
fn observe(
    e: &Ephemeris,
    position: &[f64; 3],
    velocity: &[f64; 3],
    clock_bias_m: f64,
    receive: &GpsTime,
) -> Result<Option<(f64, Observation, [f64; 3])>, ExampleError> {
    let sub = |a: &[f64; 3], b: &[f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let norm = |a: &[f64; 3]| libm::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    let dot = |a: &[f64; 3], b: &[f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let mut tau = 0.07;
    let (mut p, mut v, mut tx) = ([0.0; 3], [0.0; 3], *receive);
    for _ in 0..4 {
        tx = receive.add_seconds(-tau)?;
        let s = e.satellite_state(&tx)?;
        let th = OMEGA_EARTH * tau;
        let (st, ct) = (libm::sin(th), libm::cos(th));
        let (r, u) = (s.position_m, s.velocity_m_s);
        p = [ct * r[0] + st * r[1], -st * r[0] + ct * r[1], r[2]];
        v = [ct * u[0] + st * u[1], -st * u[0] + ct * u[1], u[2]];
        tau = norm(&sub(&p, position)) / SPEED_OF_LIGHT;
    }
    let d = sub(&p, position);
    let range = norm(&d);
    let u = [d[0] / range, d[1] / range, d[2] / range];
    let along = (-dot(position, &u)).clamp(0.0, range);
    let closest = [
        position[0] + u[0] * along,
        position[1] + u[1] * along,
        position[2] + u[2] * along,
    ];
    // hidden when the ray passes below 100 km between the receiver and the satellite (a
    // satellite above the receiver's horizontal plane has its closest point at the receiver)
    if along > 0.0 && norm(&closest) < OCCULTATION_RADIUS_M {
        return Ok(None);
    }
    let state = e.satellite_state(&tx)?;
    let t_sv = tx.add_seconds(state.clock_s)?;
    let rate = dot(&u, &sub(&v, velocity)) - SPEED_OF_LIGHT * state.clock_rate;
    let obs = Observation {
        prn: e.prn,
        transmit: t_sv,
        pseudorange_m: range + clock_bias_m - SPEED_OF_LIGHT * state.clock_s,
        doppler_hz: Some((-rate / L1_WAVELENGTH_M) as f32),
        sigma_m: 3.0,
    };
    let up = dot(&u, position) / norm(position);
    Ok(Some((up, obs, u)))
}
