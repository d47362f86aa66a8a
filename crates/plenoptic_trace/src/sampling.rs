//! Deterministic random numbers and the sampling routines the renderers share.
//!
//! Every pixel sample draws from its own [`Sampler`], seeded by (seed, pixel index, sample
//! index) through a hash, so an image does not depend on how rayon splits the work.

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// A PCG32 random stream (O'Neill 2014), seeded by hashing a key.
#[derive(Debug, Clone)]
pub struct Sampler {
    state: u64,
    inc: u64,
}

/// SplitMix64 finaliser: a good 64-bit mixing function.
pub(crate) fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl Sampler {
    /// A stream for one sample: the same (seed, pixel, sample) always gives the same numbers.
    pub fn new(seed: u64, pixel: u64, sample: u64) -> Self {
        let a = mix64(seed ^ 0x9e37_79b9_7f4a_7c15);
        let b = mix64(a ^ pixel.wrapping_mul(0xd1b5_4a32_d192_ed03));
        let c = mix64(b ^ sample.wrapping_mul(0x8cb9_2ba7_2f3d_8dd7));
        let mut s = Self {
            state: 0,
            inc: (mix64(c ^ 0x5851_f42d_4c95_7f2d) << 1) | 1,
        };
        s.next_u32();
        s.state = s.state.wrapping_add(c);
        s.next_u32();
        s
    }

    /// The next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// A uniform number in [0, 1).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Two uniform numbers in [0, 1)².
    pub fn next_2d(&mut self) -> Vec2 {
        Vec2::new(self.next_f32(), self.next_f32())
    }
}

/// An orthonormal basis around a unit normal (Duff et al. 2017).
#[derive(Debug, Clone, Copy)]
pub struct Frame {
    /// First tangent.
    pub t: Vec3,
    /// Second tangent.
    pub b: Vec3,
    /// The normal.
    pub n: Vec3,
}

impl Frame {
    /// A frame whose third axis is `n` (unit).
    pub fn from_normal(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        Self {
            t: Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
            b: Vec3::new(b, sign + n.y * n.y * a, -n.y),
            n,
        }
    }

    /// World vector from local coordinates.
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.t * v.x + self.b * v.y + self.n * v.z
    }

    /// Local coordinates of a world vector.
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }
}

/// Cosine-weighted direction on the +Z hemisphere; pdf = cosθ/π.
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let r = u.x.sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u.x).max(0.0).sqrt())
}

/// Uniform direction on the unit sphere; pdf = 1/(4π).
pub fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform barycentrics (b1, b2) on a triangle (the weights of its second and third vertex).
pub fn uniform_triangle(u: Vec2) -> Vec2 {
    let s = u.x.sqrt();
    Vec2::new(1.0 - s, u.y * s)
}

/// The power heuristic (β = 2) weight of a strategy with density `a` against one with `b`.
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 <= 0.0 || !(a2 + b2).is_finite() {
        if a.is_infinite() { 1.0 } else { 0.0 }
    } else {
        a2 / (a2 + b2)
    }
}

/// A discrete distribution sampled by inverting its cumulative sum.
#[derive(Debug, Clone, Default)]
pub struct Distribution1d {
    cdf: Vec<f32>,
    total: f32,
}

impl Distribution1d {
    /// A distribution proportional to `weights` (non-negative); empty when they sum to zero.
    pub fn new(weights: impl IntoIterator<Item = f32>) -> Self {
        let mut acc = 0.0f64;
        let mut cdf = Vec::new();
        for w in weights {
            acc += f64::from(w.max(0.0));
            cdf.push(acc as f32);
        }
        Self {
            cdf,
            total: acc as f32,
        }
    }

    /// Whether nothing can be sampled.
    pub fn is_empty(&self) -> bool {
        self.total <= 0.0
    }

    /// Draws an index; returns it with its probability.
    pub fn sample(&self, u: f32) -> (usize, f32) {
        debug_assert!(!self.is_empty());
        let target = u * self.total;
        let i = self
            .cdf
            .partition_point(|&c| c <= target)
            .min(self.cdf.len() - 1);
        (i, self.pmf(i))
    }

    /// Draws an index as [`Distribution1d::sample`] does, with `u` remapped to [0, 1) inside
    /// the chosen bin (for a continuous position in it).
    pub fn sample_remapped(&self, u: f32) -> (usize, f32, f32) {
        let (i, pmf) = self.sample(u);
        let prev = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let width = self.cdf[i] - prev;
        let r = if width > 0.0 {
            ((u * self.total - prev) / width).clamp(0.0, 0.999_999_9)
        } else {
            0.5
        };
        (i, pmf, r)
    }

    /// Number of bins.
    pub fn len(&self) -> usize {
        self.cdf.len()
    }

    /// Probability of index `i`.
    pub fn pmf(&self, i: usize) -> f32 {
        let prev = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        (self.cdf[i] - prev) / self.total
    }
}
