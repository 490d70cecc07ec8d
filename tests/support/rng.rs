//! The one random number generator of the integration tests.

use arealight::glam::{DVec2, DVec3};
use std::f64::consts::PI;

/// SplitMix64 (Steele, Lea, Flood 2014): tiny, deterministic and good enough for test inputs, so
/// that every test reproduces from its seed and the tests need no RNG crate.
#[derive(Debug, Clone)]
pub struct Rng(u64);

/// SplitMix64's increment (the golden ratio in 64 bits).
const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

impl Rng {
    /// The generator for `seed` (the seed is mixed with a constant first, so that small seeds
    /// give unrelated streams).
    pub fn new(seed: u64) -> Self {
        Rng(seed ^ GOLDEN)
    }

    /// The generator whose internal state is `state` (the seeds of tests written against the
    /// raw state).
    pub fn from_state(state: u64) -> Self {
        Rng(state)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(GOLDEN);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`, 53 random bits.
    pub fn f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.f64()
    }

    /// Uniform in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }

    /// Two uniform numbers in `[0, 1)`.
    pub fn point2(&mut self) -> DVec2 {
        DVec2::new(self.f64(), self.f64())
    }

    /// A uniform direction on the unit sphere.
    pub fn dir(&mut self) -> DVec3 {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, 2.0 * PI);
        let r = (1.0 - z * z).max(0.0).sqrt();
        DVec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}
