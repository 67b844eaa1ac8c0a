//! WGS-84 geodesy: ECEF ↔ geodetic (f64: a position on the Earth to a millimetre needs f64),
//! the local north-east-down frame, elevation and azimuth (f32: directions to 10⁻⁷ rad).

use nalgebra::{Matrix3, Vector3};

/// WGS-84 semi-major axis, m.
pub const WGS84_A: f64 = 6_378_137.0;
/// WGS-84 flattening.
pub const WGS84_F: f64 = 1.0 / 298.257_223_563;
/// First eccentricity squared.
const E2: f64 = WGS84_F * (2.0 - WGS84_F);
/// Iterations of the geodetic latitude (each gains about three orders of magnitude below
/// 1000 km height; five reach 10⁻¹² rad).
pub const GEODETIC_ITERATIONS: u32 = 5;

/// A geodetic position on WGS-84.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Geodetic {
    /// Geodetic latitude, rad.
    pub lat_rad: f64,
    /// Longitude, rad.
    pub lon_rad: f64,
    /// Height above the ellipsoid, m.
    pub height_m: f64,
}

impl Geodetic {
    /// ECEF coordinates, m.
    pub fn to_ecef(&self) -> [f64; 3] {
        let (sl, cl) = (libm::sin(self.lat_rad), libm::cos(self.lat_rad));
        let (so, co) = (libm::sin(self.lon_rad), libm::cos(self.lon_rad));
        let n = WGS84_A / libm::sqrt(1.0 - E2 * sl * sl);
        [
            (n + self.height_m) * cl * co,
            (n + self.height_m) * cl * so,
            (n * (1.0 - E2) + self.height_m) * sl,
        ]
    }

    /// From ECEF (m), by a fixed number of iterations of the latitude
    /// ([`GEODETIC_ITERATIONS`]); the height formula holds at the poles. `None` within 100 km
    /// of the Earth's centre.
    pub fn from_ecef(r: &[f64; 3]) -> Option<Self> {
        let [x, y, z] = *r;
        let p = libm::sqrt(x * x + y * y);
        if !(p.is_finite() && z.is_finite()) || libm::sqrt(p * p + z * z) < 1e5 {
            return None;
        }
        let mut lat = libm::atan2(z, p * (1.0 - E2));
        let mut height = 0.0;
        for _ in 0..GEODETIC_ITERATIONS {
            let (sl, cl) = (libm::sin(lat), libm::cos(lat));
            let n = WGS84_A / libm::sqrt(1.0 - E2 * sl * sl);
            // h = p cos φ + (z + e² N sin φ) sin φ − N
            height = p * cl + (z + E2 * n * sl) * sl - n;
            lat = libm::atan2(z, p * (1.0 - E2 * n / (n + height)));
        }
        Some(Self {
            lat_rad: lat,
            lon_rad: libm::atan2(y, x),
            height_m: height,
        })
    }

    /// `C_ne`: ECEF components to local north-east-down components.
    pub fn ecef_to_ned(&self) -> Matrix3<f32> {
        let (sl, cl) = (
            libm::sinf(self.lat_rad as f32),
            libm::cosf(self.lat_rad as f32),
        );
        let (so, co) = (
            libm::sinf(self.lon_rad as f32),
            libm::cosf(self.lon_rad as f32),
        );
        Matrix3::new(
            -sl * co,
            -sl * so,
            cl,
            -so,
            co,
            0.0,
            -cl * co,
            -cl * so,
            -sl,
        )
    }
}

/// Elevation and azimuth (rad; azimuth from north towards east in `[0, 2π)`) of a unit line
/// of sight in local north-east-down components.
pub fn elevation_azimuth(los_ned: &Vector3<f32>) -> (f32, f32) {
    let elevation = libm::asinf((-los_ned.z).clamp(-1.0, 1.0));
    let mut azimuth = libm::atan2f(los_ned.y, los_ned.x);
    if azimuth < 0.0 {
        azimuth += core::f32::consts::TAU;
    }
    (elevation, azimuth)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn geodetic_round_trip_from_the_ground_to_a_leo() {
        for &(lat, lon, h) in &[
            (50.45f64, 30.52f64, 180.0f64),
            (-33.9, 151.2, 0.0),
            (89.999, 10.0, 550e3),
            (-90.0, 0.0, 100.0),
            (0.0, -179.0, 550e3),
        ] {
            let g = Geodetic {
                lat_rad: lat.to_radians(),
                lon_rad: lon.to_radians(),
                height_m: h,
            };
            let back = Geodetic::from_ecef(&g.to_ecef()).unwrap();
            assert!((back.lat_rad - g.lat_rad).abs() < 1e-11, "{lat}");
            assert!((back.height_m - h).abs() < 1e-4, "{lat}: {}", back.height_m);
            if lat.abs() < 89.0 {
                assert!((back.lon_rad - g.lon_rad).abs() < 1e-12);
            }
        }
        assert!(Geodetic::from_ecef(&[0.0, 0.0, 10.0]).is_none());
    }

    #[test]
    fn zenith_has_ninety_degrees_elevation() {
        let g = Geodetic {
            lat_rad: 0.3,
            lon_rad: 1.2,
            height_m: 0.0,
        };
        let up = g.to_ecef();
        let n = (up[0] * up[0] + up[1] * up[1] + up[2] * up[2]).sqrt();
        let c = g.ecef_to_ned();
        let los = c * Vector3::new((up[0] / n) as f32, (up[1] / n) as f32, (up[2] / n) as f32);
        let (el, _) = elevation_azimuth(&los);
        // geocentric vs geodetic vertical differ by < 0.2°
        assert!(el > 89.7f32.to_radians(), "{}", el.to_degrees());
    }
}
