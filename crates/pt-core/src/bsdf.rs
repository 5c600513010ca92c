//! BSDF sampling: the one material, Lambertian, sampled by its cosine lobe
//! mixed with a lobe aimed at the light. A second material would add its
//! own sampler and density beside [`Scatter`], chosen by the surface's
//! material.

use spirv_std::glam::{Vec2, Vec3};

use crate::light::{GlowLobe, LightCone};
use crate::params::{FLAG_GLOW, FLAG_GLOW_SPARSE};
use crate::sampling::{PI, about_axis, cosine_polar};

/// Probability that BSDF sampling draws from the glow lobe instead of the
/// cosine lobe (with `FLAG_GLOW`): chosen by `pathtracer bench` around
/// small lights, whose surroundings outshine the rest of the room.
pub const GLOW_PROBABILITY: f32 = 0.25;

/// The glow lobe's probability with `FLAG_GLOW_SPARSE`: around large
/// lights, and in bright rooms, where the light's surroundings outshine the
/// room less. Chosen by `pathtracer bench convergence --suite` among 0.05,
/// 0.1, 0.15 and 0.25 (docs/ARCHITECTURE.md, "Per-scene defaults").
pub const GLOW_PROBABILITY_SPARSE: f32 = 0.1;

/// The glow lobe's probability under integrator `flags`: 0 without
/// `FLAG_GLOW`, [`GLOW_PROBABILITY_SPARSE`] with `FLAG_GLOW_SPARSE`, else
/// [`GLOW_PROBABILITY`]. The scalar path loop and the CPU's eight lanes
/// both take it from here.
#[inline]
pub fn glow_probability(flags: u32) -> f32 {
    if flags & FLAG_GLOW == 0 {
        0.0
    } else if flags & FLAG_GLOW_SPARSE != 0 {
        GLOW_PROBABILITY_SPARSE
    } else {
        GLOW_PROBABILITY
    }
}

/// BSDF sampling at a diffuse vertex: the cosine lobe about the shading
/// normal, mixed with the glow lobe around the light. One draw picks a lobe
/// with fixed probabilities and the estimate divides by the mixture's
/// density (one-sample MIS with the balance heuristic; Veach 1997, 9.2.4),
/// which is never below 3/4 of the cosine lobe's: no direction the BSDF
/// reaches gets a large weight.
///
/// `repr(C)` in this order: the path loop holds one across a branch, and
/// naga, which rounds a struct with a `Vec3` (the glow lobe) up to 16 bytes
/// and aligns it to 16, rejects the kernel where Rust's own order puts a
/// member inside that rounding.
#[repr(C)]
pub struct Scatter {
    n: Vec3,
    /// 0 without the glow lobe.
    glow_probability: f32,
    glow: GlowLobe,
}

impl Scatter {
    /// The cosine lobe about +z: a placeholder where no direction is drawn.
    pub const NONE: Self = Self { n: Vec3::Z, glow: GlowLobe::UNUSED, glow_probability: 0.0 };

    /// Sampling about unit normal `n`, with the glow lobe around `cone`
    /// picked with probability `glow` when that is not 0, the cone is not
    /// empty and the lobe is not wholly below the surface (the unlit side of
    /// a sphere keeps all of its samples). Without it the lobe is not built
    /// (a logarithm per vertex).
    #[inline]
    pub fn new(n: Vec3, cone: &LightCone, glow: f32) -> Self {
        let on = glow > 0.0 && !cone.is_empty();
        let lobe = if on { GlowLobe::new(cone) } else { GlowLobe::UNUSED };
        let glow_probability = if on && !lobe.below_horizon(n) { glow } else { 0.0 };
        Self { n, glow: lobe, glow_probability }
    }

    /// A direction from `u` in [0, 1)^2: `u.x` picks the lobe and is
    /// stretched back to [0, 1) for it, which keeps its stratification.
    ///
    /// Both lobes are symmetric about an axis, so only the axis and the
    /// polar angle depend on the pick; the basis and the turn about the axis
    /// are shared. SIMD lanes that pick different lobes then run one basis
    /// and one sine and cosine, not both lobes' (a GPU runs both sides of a
    /// divergent branch).
    #[inline]
    pub fn sample(&self, u: Vec2) -> Vec3 {
        let p = self.glow_probability;
        let (axis, (cos_theta, sin_theta)) = if u.x < p {
            (self.glow.axis(), self.glow.polar(u.x / p))
        } else {
            (self.n, cosine_polar((u.x - p) / (1.0 - p)))
        };
        about_axis(axis, cos_theta, sin_theta, u.y)
    }

    /// Solid-angle density of [`Scatter::sample`] at unit `dir`.
    #[inline]
    pub fn pdf(&self, dir: Vec3) -> f32 {
        let p = self.glow_probability;
        let cosine = self.n.dot(dir).max(0.0) * (1.0 / PI);
        let glow = if p > 0.0 { self.glow.pdf(dir) } else { 0.0 };
        (1.0 - p) * cosine + p * glow
    }
}
