//! The display transform: exposure, tone map, sRGB encoding, 8-bit packing.

#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;

use spirv_std::glam::{Vec3, Vec4};

use crate::params::TONEMAP_ACES;

/// The ACES filmic curve fitted by Narkowicz ("ACES Filmic Tone Mapping
/// Curve", 2015), per channel, clamped to [0, 1].
pub fn aces_filmic(x: Vec3) -> Vec3 {
    let a = 2.51;
    let b = 0.03;
    let c = 2.43;
    let d = 0.59;
    let e = 0.14;
    ((x * (x * a + b)) / (x * (x * c + d) + e)).clamp(Vec3::ZERO, Vec3::ONE)
}

/// Linear [0, 1] to the sRGB transfer curve (IEC 61966-2-1).
pub fn srgb_encode(c: f32) -> f32 {
    if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 }
}

/// Exposure (stops), then the tone mapper, then sRGB: a display colour with
/// channels in [0, 1]. Non-finite or negative input gives black.
pub fn display_color(radiance: Vec3, exposure: f32, tonemap: u32) -> Vec3 {
    let scaled = (radiance * exposure.exp2()).max(Vec3::ZERO);
    let mapped = if tonemap == TONEMAP_ACES { aces_filmic(scaled) } else { scaled.min(Vec3::ONE) };
    Vec3::new(srgb_encode(mapped.x), srgb_encode(mapped.y), srgb_encode(mapped.z))
}

/// Packs a colour in [0, 1] as RGBA8 (red in the low byte, alpha 255), the
/// byte order of `Rgba8Unorm` and of PNG's RGBA.
pub fn pack_rgba8(c: Vec3) -> u32 {
    quantize(c.x) | (quantize(c.y) << 8) | (quantize(c.z) << 16) | (255 << 24)
}

/// The inverse of [`pack_rgba8`]: channels in [0, 1].
pub fn unpack_rgba8(p: u32) -> Vec4 {
    Vec4::new(unorm8(p), unorm8(p >> 8), unorm8(p >> 16), unorm8(p >> 24))
}

/// The low byte of `p` as a fraction of 255.
fn unorm8(p: u32) -> f32 {
    (p & 255) as f32 * (1.0 / 255.0)
}

/// Clip-space position of vertex `index` (0, 1, 2) of one triangle that
/// covers the whole viewport: (-1, -1), (3, -1), (-1, 3).
pub fn fullscreen_triangle(index: u32) -> Vec4 {
    let x = ((index << 1) & 2) as f32;
    let y = (index & 2) as f32;
    Vec4::new(x * 2.0 - 1.0, y * 2.0 - 1.0, 0.0, 1.0)
}

/// [0, 1] to 0..=255, rounded to nearest. NaN fails both comparisons: 0.
fn quantize(v: f32) -> u32 {
    let v = if v > 0.0 { if v < 1.0 { v } else { 1.0 } } else { 0.0 };
    (v * 255.0 + 0.5) as u32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::TONEMAP_CLAMP;

    #[test]
    fn srgb_curve_end_points_and_knee() {
        assert_eq!(srgb_encode(0.0), 0.0);
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-6);
        // Both pieces meet at the knee to within 1e-7.
        let k = 0.003_130_8f32;
        assert!((12.92 * k - (1.055 * k.powf(1.0 / 2.4) - 0.055)).abs() < 1e-6);
        assert!((srgb_encode(0.5) - 0.735_356_7).abs() < 1e-5);
    }

    #[test]
    fn packing_is_rgba_little_endian_and_rounds() {
        assert_eq!(pack_rgba8(Vec3::new(1.0, 0.0, 0.5)), 0xff_80_00_ff);
        assert_eq!(pack_rgba8(Vec3::new(f32::NAN, 2.0, -1.0)), 0xff_00_ff_00);
    }

    #[test]
    fn unpack_inverts_pack() {
        for p in [0u32, 0xff_80_00_ff, 0x12_34_56_78, u32::MAX] {
            let c = unpack_rgba8(p);
            assert_eq!(pack_rgba8(c.truncate()) & 0x00ff_ffff, p & 0x00ff_ffff);
            assert_eq!((c.w * 255.0).round() as u32, p >> 24);
        }
    }

    #[test]
    fn fullscreen_triangle_covers_the_viewport() {
        let v: [Vec4; 3] = [0, 1, 2].map(fullscreen_triangle);
        assert_eq!([v[0].x, v[0].y, v[1].x, v[1].y, v[2].x, v[2].y], [-1.0, -1.0, 3.0, -1.0, -1.0, 3.0]);
    }

    #[test]
    fn exposure_doubles_per_stop_and_tone_mappers_saturate() {
        let c = display_color(Vec3::splat(0.25), 1.0, TONEMAP_CLAMP);
        assert!((c.x - srgb_encode(0.5)).abs() < 1e-6);
        // 1.055 * 1 - 0.055 is 1 to within one f32 ulp.
        assert!((display_color(Vec3::splat(1e9), 0.0, TONEMAP_CLAMP) - Vec3::ONE).length() < 1e-6);
        assert!((display_color(Vec3::splat(1e9), 0.0, TONEMAP_ACES) - Vec3::ONE).length() < 1e-3);
        assert_eq!(display_color(Vec3::ZERO, 0.0, TONEMAP_ACES), Vec3::ZERO);
    }
}
