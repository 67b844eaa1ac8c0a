//! The synthesizer's own C/A code generator (independent of the core's): G1 ⊕ G2 delayed by
//! the PRN's "code delay" of IS-GPS-200 Table 3-Ia.

/// G2 delay (chips) of PRN 1–32, IS-GPS-200 Table 3-Ia.
const G2_DELAY: [usize; 32] = [
    5, 6, 7, 8, 17, 18, 139, 140, 141, 251, 252, 254, 255, 256, 257, 258, 469, 470, 471, 472, 473,
    474, 509, 512, 513, 514, 515, 516, 859, 860, 861, 862,
];

/// The ±1 chips (logic 0 → +1) of PRN `prn` (1–32), 1023 values; all +1 for other numbers.
pub fn ca_code(prn: u8) -> Vec<f32> {
    if !(1..=32).contains(&prn) {
        return vec![1.0; 1023];
    }
    let mut g1 = [0u8; 1023];
    let mut g2 = [0u8; 1023];
    let (mut r1, mut r2) = (0x3ffu16, 0x3ffu16);
    for k in 0..1023 {
        g1[k] = ((r1 >> 9) & 1) as u8;
        g2[k] = ((r2 >> 9) & 1) as u8;
        let f1 = ((r1 >> 2) ^ (r1 >> 9)) & 1;
        let f2 = ((r2 >> 1) ^ (r2 >> 2) ^ (r2 >> 5) ^ (r2 >> 7) ^ (r2 >> 8) ^ (r2 >> 9)) & 1;
        r1 = ((r1 << 1) | f1) & 0x3ff;
        r2 = ((r2 << 1) | f2) & 0x3ff;
    }
    let delay = G2_DELAY[prn as usize - 1];
    (0..1023)
        .map(|k| {
            let bit = g1[k] ^ g2[(k + 1023 - delay) % 1023];
            1.0 - 2.0 * f32::from(bit)
        })
        .collect()
}
