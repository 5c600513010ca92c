//! Helpers shared by pt-core's tests.

pub mod chi2;

use std::f64::consts::PI;

use spirv_std::glam::Vec3;

use crate::rng::Rng;

/// Significance of each chi-square test: 1% family-wise over the 7
/// sampling tests (Sidak), as one run of them would be judged together.
pub fn chi2_alpha() -> f64 {
    1.0 - 0.99f64.powf(1.0 / 7.0)
}

/// Counts of `n` directions from `sample` in the frame of `axis`: `bands`
/// bands of equal width in `1 - cos` of the angle to the axis over [0,
/// `max_x`], each cut in `sectors` equal sectors of the turn about it, then
/// one cell for directions outside. Directions are normalised in f64 (the
/// test is about where they point; an f32 unit vector is unit only to
/// ~1e-7), and a hair of slack at both ends of the range absorbs rounding.
pub fn cap_histogram(
    n: usize,
    axis: Vec3,
    max_x: f64,
    (bands, sectors): (usize, usize),
    sample: impl Fn(&mut Rng) -> Vec3,
) -> Vec<f64> {
    let (tb, bb) = crate::sampling::orthonormal_basis(axis);
    let (axis, tb, bb) = (axis.as_dvec3(), tb.as_dvec3(), bb.as_dvec3());
    let mut rng = Rng::new(5, 6, 7, 8, 9);
    let mut observed = vec![0.0; bands * sectors + 1];
    for _ in 0..n {
        let d = sample(&mut rng).as_dvec3().normalize();
        let band = (1.0 - d.dot(axis)) / max_x;
        let phi = d.dot(bb).atan2(d.dot(tb)).rem_euclid(2.0 * PI);
        let cell = if !(-1e-3..=1.0 + 1e-3).contains(&band) {
            bands * sectors
        } else {
            ((band * bands as f64) as usize).min(bands - 1) * sectors
                + ((phi / (2.0 * PI) * sectors as f64) as usize).min(sectors - 1)
        };
        observed[cell] += 1.0;
    }
    observed
}

/// A uniformly distributed unit direction.
pub fn random_dir(rng: &mut Rng) -> Vec3 {
    let z = 1.0 - 2.0 * rng.next_f32();
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * rng.next_f32();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// The default room closed by a front wall: floor, ceiling, back, left,
/// right and front, all of albedo 0.73.
pub fn closed_room() -> [crate::wall::Wall; 6] {
    use crate::wall::Wall;
    let v = Vec3::new;
    let a = Vec3::splat(0.73);
    [
        Wall::new(v(-1.0, 0.0, 1.0), v(2.0, 0.0, 0.0), v(0.0, 0.0, -2.0), a),
        Wall::new(v(-1.0, 2.0, 1.0), v(2.0, 0.0, 0.0), v(0.0, 0.0, -2.0), a),
        Wall::new(v(-1.0, 0.0, -1.0), v(2.0, 0.0, 0.0), v(0.0, 2.0, 0.0), a),
        Wall::new(v(-1.0, 0.0, 1.0), v(0.0, 0.0, -2.0), v(0.0, 2.0, 0.0), a),
        Wall::new(v(1.0, 0.0, 1.0), v(0.0, 0.0, -2.0), v(0.0, 2.0, 0.0), a),
        Wall::new(v(-1.0, 0.0, 1.0), v(2.0, 0.0, 0.0), v(0.0, 2.0, 0.0), a),
    ]
}

/// The scales at which spawned rays must not re-hit their own surface.
pub const SCALES: [f32; 5] = [1e-3, 1e-1, 1.0, 1e2, 1e4];
