//! The microsat run's `--nmea` output: the heading of body `+x` in the local north-east-down
//! frame at the spacecraft (from the orbit the attitude truth flies; the flight computer has
//! the same from its navigation solution). Without an orbit (the detumbling variant) the
//! sentences say "not valid".

use gnss_attitude::receiver::ReceiverAttitude;

use super::world::{Motion, World};

/// Hands one attitude to the NMEA sink (a no-op without `--nmea`).
pub fn record(attitude: &ReceiverAttitude, world: &World, t: f64) {
    let frame = match &world.motion {
        Motion::Nadir(m) => Some(crate::nmea_out::ned_from_eci(&m.orbit.eci(t).r)),
        Motion::Detumbling(_) => None,
    };
    crate::nmea_out::record(attitude, frame.as_ref());
}
