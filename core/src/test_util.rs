//! Helpers shared by the unit tests of the core (compiled only for `cargo test`).

use glam::Vec3;

/// A 64-bit LCG (Knuth's MMIX constants) giving `f32` in `[0, 1)` with 24 random bits.
pub fn lcg(state: &mut u64) -> f32 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*state >> 40) as f32) / ((1u64 << 24) as f32)
}

/// A random unit vector (rejection sampling in the unit ball).
pub fn unit_vec(s: &mut u64) -> Vec3 {
    loop {
        let v = Vec3::new(lcg(s) * 2.0 - 1.0, lcg(s) * 2.0 - 1.0, lcg(s) * 2.0 - 1.0);
        let l = v.length();
        if l > 0.1 && l <= 1.0 {
            return v / l;
        }
    }
}
