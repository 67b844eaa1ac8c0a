//! Signal delays of the atmosphere for a single-frequency user: the broadcast (Klobuchar)
//! ionosphere of IS-GPS-200 20.3.3.5.2.5 and a simple troposphere (standard-atmosphere zenith
//! delay scaled with height, the RTCA DO-229 mapping function).
//!
//! Both are for ground users. A receiver in low Earth orbit (550 km) is above the troposphere
//! and above most of the ionosphere, where the Klobuchar model (the whole vertical column)
//! does not apply: [`super::solution::SolverConfig::leo`] switches both off.
//!
//! Precision: f32 (delays of metres to tens of metres, to a centimetre).

use super::message::KlobucharParameters;
use super::SPEED_OF_LIGHT;

/// IS-GPS-200's value of π for semicircles.
const PI: f32 = core::f32::consts::PI;
/// Seconds per day.
const DAY_S: f32 = 86_400.0;
/// Zenith tropospheric delay at sea level, m (standard atmosphere).
pub const ZENITH_TROPOSPHERE_M: f32 = 2.3;
/// Scale height of the tropospheric delay, m.
pub const TROPOSPHERE_SCALE_HEIGHT_M: f32 = 8_600.0;

/// The Klobuchar ionospheric delay of the L1 signal, m, for a user at geodetic latitude
/// `lat_rad`, longitude `lon_rad`, a satellite at elevation `el_rad` and azimuth `az_rad`, at
/// GPS time of week `tow_s`.
pub fn klobuchar_delay_m(
    params: &KlobucharParameters,
    lat_rad: f32,
    lon_rad: f32,
    el_rad: f32,
    az_rad: f32,
    tow_s: f64,
) -> f32 {
    // semicircles
    let e = el_rad / PI;
    let (phi_u, lambda_u) = (lat_rad / PI, lon_rad / PI);
    // Earth-centred angle ψ, ionospheric pierce point latitude and longitude
    let psi = 0.0137 / (e + 0.11) - 0.022;
    let phi_i = (phi_u + psi * libm::cosf(az_rad)).clamp(-0.416, 0.416);
    let lambda_i = lambda_u + psi * libm::sinf(az_rad) / libm::cosf(phi_i * PI);
    // geomagnetic latitude of the pierce point
    let phi_m = phi_i + 0.064 * libm::cosf((lambda_i - 1.617) * PI);
    // local time at the pierce point, s
    let local = libm::fmod(4.32e4 * f64::from(lambda_i) + tow_s, f64::from(DAY_S)) as f32;
    let t = if local < 0.0 { local + DAY_S } else { local };
    // obliquity factor
    let f = 1.0 + 16.0 * (0.53 - e) * (0.53 - e) * (0.53 - e);
    let poly = |c: &[f32; 4]| c[0] + phi_m * (c[1] + phi_m * (c[2] + phi_m * c[3]));
    let amp = poly(&params.alpha).max(0.0);
    let per = poly(&params.beta).max(72_000.0);
    let x = 2.0 * PI * (t - 50_400.0) / per;
    let night = 5e-9f32;
    let delay_s = if libm::fabsf(x) < 1.57 {
        f * (night + amp * (1.0 - x * x / 2.0 + x * x * x * x / 24.0))
    } else {
        f * night
    };
    delay_s * SPEED_OF_LIGHT as f32
}

/// Tropospheric delay, m, at height `height_m` (clamped at 0 below sea level) for elevation
/// `el_rad`: `2.3 m · e^(−h/8.6 km) · 1.001 / √(0.002001 + sin² el)`.
pub fn troposphere_delay_m(height_m: f32, el_rad: f32) -> f32 {
    let zenith = ZENITH_TROPOSPHERE_M * libm::expf(-height_m.max(0.0) / TROPOSPHERE_SCALE_HEIGHT_M);
    let s = libm::sinf(el_rad);
    zenith * 1.001 / crate::sqrtf(0.002_001 + s * s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A typical broadcast set.
    fn params() -> KlobucharParameters {
        KlobucharParameters {
            alpha: [1.118e-8, 7.451e-9, -5.961e-8, -5.961e-8],
            beta: [90_112.0, 16_384.0, -196_608.0, -131_072.0],
        }
    }

    #[test]
    fn klobuchar_day_and_night_and_obliquity() {
        let p = params();
        let lat = 40f32.to_radians();
        let lon = -100f32.to_radians();
        // local 14:00 at the pierce point ~ GPS 14:00 + 6.7 h
        let day = klobuchar_delay_m(&p, lat, lon, 90f32.to_radians(), 0.0, 20.7 * 3600.0);
        let night = klobuchar_delay_m(&p, lat, lon, 90f32.to_radians(), 0.0, 8.7 * 3600.0);
        let low = klobuchar_delay_m(&p, lat, lon, 10f32.to_radians(), 0.0, 20.7 * 3600.0);
        // night: 5 ns × F(90°) = 1.5 m
        assert!((night - 5e-9 * 299_792_458.0 * (1.0 + 16.0 * (0.03f32).powi(3))).abs() < 0.05);
        assert!(day > 2.0 && day < 15.0, "{day}");
        assert!(low > 2.0 * day, "{low} vs {day}");
    }

    #[test]
    fn troposphere_at_zenith_low_elevation_and_altitude() {
        assert!((troposphere_delay_m(0.0, core::f32::consts::FRAC_PI_2) - 2.3).abs() < 0.01);
        let low = troposphere_delay_m(0.0, 5f32.to_radians());
        assert!(low > 20.0 && low < 30.0, "{low}");
        assert!(troposphere_delay_m(550e3, 0.5) < 1e-20);
    }
}
