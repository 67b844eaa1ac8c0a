//! The contents of the LNAV subframes (IS-GPS-200 20.3.3, Figure 20-1, Tables 20-I, 20-III,
//! 20-VI, 20-VII, 20-IX, 20-X): bit fields, two's complement, fields split over two words,
//! scale factors. Angles are converted from semicircles to radians with IS-GPS-200's
//! `π = 3.1415926535898`.
//!
//! Precision: every orbit and clock field is `f64` (a 32-bit field at `2⁻³¹` semicircles
//! needs more than f32's 24 bits); the ionosphere parameters are `f32` (8-bit fields, exact).

use super::subframe::Subframe;
use super::GPS_PI;

/// `2ⁿ` as an exact `f64` constant.
const fn pow2(n: i32) -> f64 {
    let mut x = 1.0f64;
    let mut k = 0;
    if n >= 0 {
        while k < n {
            x *= 2.0;
            k += 1;
        }
    } else {
        while k < -n {
            x *= 0.5;
            k += 1;
        }
    }
    x
}

/// Field `len` bits long starting at bit `first` (1-based, IS-GPS-200 numbering within the
/// word's 24 data bits) of word `word` (1-based).
fn field(words: &[u32; 10], word: usize, first: u32, len: u32) -> u32 {
    let value = word
        .checked_sub(1)
        .and_then(|w| words.get(w))
        .copied()
        .unwrap_or(0);
    let shift = 24u32.saturating_sub(first.saturating_add(len).saturating_sub(1));
    let mask = if len >= 32 {
        u32::MAX
    } else {
        (1u32 << len) - 1
    };
    (value >> shift.min(31)) & mask
}

/// Two's complement of a `bits`-wide field.
fn signed(value: u32, bits: u32) -> i32 {
    if bits == 0 || bits >= 32 {
        return value as i32;
    }
    let shift = 32 - bits;
    ((value << shift) as i32) >> shift
}

/// A field split over two words: `hi_len` bits of `hi_word` from bit `hi_first`, then the 24
/// bits of `lo_word` (the orbit fields of subframes 2 and 3).
fn split_u32(words: &[u32; 10], hi_word: usize, hi_first: u32, hi_len: u32, lo_word: usize) -> u32 {
    (field(words, hi_word, hi_first, hi_len) << 24) | field(words, lo_word, 1, 24)
}

fn semicircles(value: f64) -> f64 {
    value * GPS_PI
}

/// Subframe 1: week, health, clock correction and group delay.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ClockData {
    /// Week number modulo 1024 (of the transmission).
    pub week_mod_1024: u16,
    /// Codes on L2 (2 bits).
    pub l2_codes: u8,
    /// User range accuracy index (0–15).
    pub ura_index: u8,
    /// Six-bit SV health (0 = all signals and data healthy).
    pub health: u8,
    /// Issue of data, clock (10 bits).
    pub iodc: u16,
    /// L1–L2 group delay `T_GD`, s.
    pub tgd_s: f64,
    /// Clock reference time `t_oc`, s of the week.
    pub toc_s: f64,
    /// Clock drift rate `a_f2`, s/s².
    pub af2: f64,
    /// Clock drift `a_f1`, s/s.
    pub af1: f64,
    /// Clock bias `a_f0`, s.
    pub af0: f64,
}

/// Subframe 2: the first half of the ephemeris.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct OrbitData2 {
    /// Issue of data, ephemeris.
    pub iode: u8,
    /// Sine harmonic correction to the orbit radius `C_rs`, m.
    pub crs: f64,
    /// Mean motion difference `Δn`, rad/s.
    pub delta_n: f64,
    /// Mean anomaly at the reference time `M0`, rad.
    pub m0: f64,
    /// Cosine harmonic correction to the argument of latitude `C_uc`, rad.
    pub cuc: f64,
    /// Eccentricity `e`.
    pub e: f64,
    /// Sine harmonic correction to the argument of latitude `C_us`, rad.
    pub cus: f64,
    /// Square root of the semi-major axis `√A`, √m.
    pub sqrt_a: f64,
    /// Ephemeris reference time `t_oe`, s of the week.
    pub toe_s: f64,
    /// Fit interval flag (0: 4 hours).
    pub fit_interval: bool,
    /// Age of data offset, s.
    pub aodo_s: u32,
}

/// Subframe 3: the second half of the ephemeris.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct OrbitData3 {
    /// Cosine harmonic correction to the inclination `C_ic`, rad.
    pub cic: f64,
    /// Longitude of the ascending node at the weekly epoch `Ω0`, rad.
    pub omega0: f64,
    /// Sine harmonic correction to the inclination `C_is`, rad.
    pub cis: f64,
    /// Inclination at the reference time `i0`, rad.
    pub i0: f64,
    /// Cosine harmonic correction to the orbit radius `C_rc`, m.
    pub crc: f64,
    /// Argument of perigee `ω`, rad.
    pub omega: f64,
    /// Rate of right ascension `Ω̇`, rad/s.
    pub omega_dot: f64,
    /// Issue of data, ephemeris.
    pub iode: u8,
    /// Rate of inclination `IDOT`, rad/s.
    pub idot: f64,
}

/// One satellite's almanac (subframe 5 pages 1–24, subframe 4 pages 2–5 and 7–10).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AlmanacData {
    /// The satellite (SV ID 1–32).
    pub prn: u8,
    /// Eccentricity.
    pub e: f64,
    /// Almanac reference time `t_oa`, s of the week.
    pub toa_s: f64,
    /// Inclination (0.30 semicircles + `δi`), rad.
    pub i0: f64,
    /// Rate of right ascension, rad/s.
    pub omega_dot: f64,
    /// Eight-bit SV health (0 = healthy).
    pub health: u8,
    /// Square root of the semi-major axis, √m.
    pub sqrt_a: f64,
    /// Longitude of the ascending node at the weekly epoch, rad.
    pub omega0: f64,
    /// Argument of perigee, rad.
    pub omega: f64,
    /// Mean anomaly at the reference time, rad.
    pub m0: f64,
    /// Clock bias, s.
    pub af0: f64,
    /// Clock drift, s/s.
    pub af1: f64,
}

/// Subframe 5 page 25 (SV ID 51): the almanac's reference time and week, health of SV 1–24.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AlmanacReference {
    /// Almanac reference time `t_oa`, s of the week.
    pub toa_s: u32,
    /// Almanac reference week modulo 256.
    pub week_mod_256: u8,
    /// Six-bit health of SV 1–24.
    pub health: [u8; 24],
}

/// The broadcast (Klobuchar) ionosphere model: coefficients of the amplitude and period
/// polynomials in geomagnetic latitude (semicircles).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct KlobucharParameters {
    /// `α0 … α3`: s, s/semicircle, s/semicircle², s/semicircle³.
    pub alpha: [f32; 4],
    /// `β0 … β3`: s, s/semicircle, s/semicircle², s/semicircle³.
    pub beta: [f32; 4],
}

/// GPS–UTC parameters (subframe 4 page 18).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct UtcParameters {
    /// Bias `A0`, s.
    pub a0_s: f64,
    /// Drift `A1`, s/s.
    pub a1: f64,
    /// Reference time `t_ot`, s of the week.
    pub tot_s: u32,
    /// Reference week `WN_t` modulo 256.
    pub wnt_mod_256: u8,
    /// Current leap seconds `Δt_LS`, s.
    pub delta_t_ls_s: i8,
    /// Week of the next leap second `WN_LSF` modulo 256.
    pub wn_lsf_mod_256: u8,
    /// Day number of the next leap second (1–7).
    pub day_number: u8,
    /// Leap seconds after it `Δt_LSF`, s.
    pub delta_t_lsf_s: i8,
}

/// What one subframe carries.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NavMessage {
    /// Subframe 1.
    Clock(ClockData),
    /// Subframe 2.
    Orbit2(OrbitData2),
    /// Subframe 3.
    Orbit3(OrbitData3),
    /// An almanac page (subframe 4 or 5, SV ID 1–32).
    Almanac(AlmanacData),
    /// Subframe 5 page 25.
    AlmanacReference(AlmanacReference),
    /// Subframe 4 page 18.
    IonosphereUtc(KlobucharParameters, UtcParameters),
    /// Any other page of subframes 4 and 5 (reserved, special messages, health of SV 25–32,
    /// dummy pages of SV ID 0), or a page whose data ID is not 01.
    Other {
        /// Subframe id (4 or 5).
        subframe: u8,
        /// SV (page) ID.
        sv_id: u8,
    },
}

/// SV ID of subframe 4 page 18.
pub const SV_ID_IONO_UTC: u8 = 56;
/// SV ID of subframe 5 page 25.
pub const SV_ID_ALMANAC_REFERENCE: u8 = 51;

/// The contents of a subframe, by its id and (for subframes 4 and 5) its SV ID.
pub fn decode(subframe: &Subframe) -> NavMessage {
    let w = &subframe.words;
    match subframe.id() {
        1 => NavMessage::Clock(decode_clock(w)),
        2 => NavMessage::Orbit2(decode_orbit2(w)),
        3 => NavMessage::Orbit3(decode_orbit3(w)),
        id => {
            let data_id = field(w, 3, 1, 2);
            let sv_id = field(w, 3, 3, 6) as u8;
            if data_id != 0b01 {
                return NavMessage::Other {
                    subframe: id,
                    sv_id,
                };
            }
            match (id, sv_id) {
                (_, 1..=32) => NavMessage::Almanac(decode_almanac(w, sv_id)),
                (5, SV_ID_ALMANAC_REFERENCE) => {
                    NavMessage::AlmanacReference(decode_almanac_reference(w))
                }
                (4, SV_ID_IONO_UTC) => {
                    let (iono, utc) = decode_iono_utc(w);
                    NavMessage::IonosphereUtc(iono, utc)
                }
                _ => NavMessage::Other {
                    subframe: id,
                    sv_id,
                },
            }
        }
    }
}

fn decode_clock(w: &[u32; 10]) -> ClockData {
    let iodc = (field(w, 3, 23, 2) << 8) | field(w, 8, 1, 8);
    ClockData {
        week_mod_1024: field(w, 3, 1, 10) as u16,
        l2_codes: field(w, 3, 11, 2) as u8,
        ura_index: field(w, 3, 13, 4) as u8,
        health: field(w, 3, 17, 6) as u8,
        iodc: iodc as u16,
        tgd_s: f64::from(signed(field(w, 7, 17, 8), 8)) * pow2(-31),
        toc_s: f64::from(field(w, 8, 9, 16)) * pow2(4),
        af2: f64::from(signed(field(w, 9, 1, 8), 8)) * pow2(-55),
        af1: f64::from(signed(field(w, 9, 9, 16), 16)) * pow2(-43),
        af0: f64::from(signed(field(w, 10, 1, 22), 22)) * pow2(-31),
    }
}

fn decode_orbit2(w: &[u32; 10]) -> OrbitData2 {
    OrbitData2 {
        iode: field(w, 3, 1, 8) as u8,
        crs: f64::from(signed(field(w, 3, 9, 16), 16)) * pow2(-5),
        delta_n: semicircles(f64::from(signed(field(w, 4, 1, 16), 16)) * pow2(-43)),
        m0: semicircles(f64::from(split_u32(w, 4, 17, 8, 5) as i32) * pow2(-31)),
        cuc: f64::from(signed(field(w, 6, 1, 16), 16)) * pow2(-29),
        e: f64::from(split_u32(w, 6, 17, 8, 7)) * pow2(-33),
        cus: f64::from(signed(field(w, 8, 1, 16), 16)) * pow2(-29),
        sqrt_a: f64::from(split_u32(w, 8, 17, 8, 9)) * pow2(-19),
        toe_s: f64::from(field(w, 10, 1, 16)) * pow2(4),
        fit_interval: field(w, 10, 17, 1) == 1,
        aodo_s: field(w, 10, 18, 5) * 900,
    }
}

fn decode_orbit3(w: &[u32; 10]) -> OrbitData3 {
    OrbitData3 {
        cic: f64::from(signed(field(w, 3, 1, 16), 16)) * pow2(-29),
        omega0: semicircles(f64::from(split_u32(w, 3, 17, 8, 4) as i32) * pow2(-31)),
        cis: f64::from(signed(field(w, 5, 1, 16), 16)) * pow2(-29),
        i0: semicircles(f64::from(split_u32(w, 5, 17, 8, 6) as i32) * pow2(-31)),
        crc: f64::from(signed(field(w, 7, 1, 16), 16)) * pow2(-5),
        omega: semicircles(f64::from(split_u32(w, 7, 17, 8, 8) as i32) * pow2(-31)),
        omega_dot: semicircles(f64::from(signed(field(w, 9, 1, 24), 24)) * pow2(-43)),
        iode: field(w, 10, 1, 8) as u8,
        idot: semicircles(f64::from(signed(field(w, 10, 9, 14), 14)) * pow2(-43)),
    }
}

fn decode_almanac(w: &[u32; 10], prn: u8) -> AlmanacData {
    let af0 = (field(w, 10, 1, 8) << 3) | field(w, 10, 20, 3);
    AlmanacData {
        prn,
        e: f64::from(field(w, 3, 9, 16)) * pow2(-21),
        toa_s: f64::from(field(w, 4, 1, 8)) * pow2(12),
        i0: semicircles(0.30 + f64::from(signed(field(w, 4, 9, 16), 16)) * pow2(-19)),
        omega_dot: semicircles(f64::from(signed(field(w, 5, 1, 16), 16)) * pow2(-38)),
        health: field(w, 5, 17, 8) as u8,
        sqrt_a: f64::from(field(w, 6, 1, 24)) * pow2(-11),
        omega0: semicircles(f64::from(signed(field(w, 7, 1, 24), 24)) * pow2(-23)),
        omega: semicircles(f64::from(signed(field(w, 8, 1, 24), 24)) * pow2(-23)),
        m0: semicircles(f64::from(signed(field(w, 9, 1, 24), 24)) * pow2(-23)),
        af0: f64::from(signed(af0, 11)) * pow2(-20),
        af1: f64::from(signed(field(w, 10, 9, 11), 11)) * pow2(-38),
    }
}

fn decode_almanac_reference(w: &[u32; 10]) -> AlmanacReference {
    let mut health = [0u8; 24];
    // four 6-bit health fields per word, words 4–9
    for (k, h) in health.iter_mut().enumerate() {
        let word = 4 + k / 4;
        let first = 1 + 6 * (k % 4) as u32;
        *h = field(w, word, first, 6) as u8;
    }
    AlmanacReference {
        toa_s: field(w, 3, 9, 8) << 12,
        week_mod_256: field(w, 3, 17, 8) as u8,
        health,
    }
}

fn decode_iono_utc(w: &[u32; 10]) -> (KlobucharParameters, UtcParameters) {
    let s8 = |word: usize, first: u32| signed(field(w, word, first, 8), 8) as f32;
    let p2 = |n: i32| pow2(n) as f32;
    let iono = KlobucharParameters {
        alpha: [
            s8(3, 9) * p2(-30),
            s8(3, 17) * p2(-27),
            s8(4, 1) * p2(-24),
            s8(4, 9) * p2(-24),
        ],
        beta: [
            s8(4, 17) * p2(11),
            s8(5, 1) * p2(14),
            s8(5, 9) * p2(16),
            s8(5, 17) * p2(16),
        ],
    };
    let a0 = (field(w, 7, 1, 24) << 8) | field(w, 8, 1, 8);
    let utc = UtcParameters {
        a0_s: f64::from(a0 as i32) * pow2(-30),
        a1: f64::from(signed(field(w, 6, 1, 24), 24)) * pow2(-50),
        tot_s: field(w, 8, 9, 8) << 12,
        wnt_mod_256: field(w, 8, 17, 8) as u8,
        delta_t_ls_s: signed(field(w, 9, 1, 8), 8) as i8,
        wn_lsf_mod_256: field(w, 9, 9, 8) as u8,
        day_number: field(w, 9, 17, 8) as u8,
        delta_t_lsf_s: signed(field(w, 10, 1, 8), 8) as i8,
    };
    (iono, utc)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_two_complement_and_split_words() {
        let mut w = [0u32; 10];
        w[3] = 0xAB_CDEF;
        assert_eq!(field(&w, 4, 1, 8), 0xAB);
        assert_eq!(field(&w, 4, 17, 8), 0xEF);
        assert_eq!(field(&w, 4, 1, 24), 0xAB_CDEF);
        assert_eq!(signed(0xFF, 8), -1);
        assert_eq!(signed(0x80, 8), -128);
        assert_eq!(signed(0x7F, 8), 127);
        assert_eq!(signed(0x20_0000, 22), -(1 << 21));
        w[4] = 0x12_3456;
        // M0: 8 MSBs in word 4 bits 17–24, 24 LSBs in word 5
        assert_eq!(split_u32(&w, 4, 17, 8, 5), 0xEF12_3456);
        assert_eq!(split_u32(&w, 4, 17, 8, 5) as i32, -0x10ED_CBAA);
        assert_eq!(pow2(-31), 1.0 / 2_147_483_648.0);
        assert_eq!(pow2(12), 4096.0);
    }
}
