//! The display transform: exposure, tone map, sRGB encoding, 8-bit packing.

#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;

use spirv_std::glam::Vec3;

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
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// Exposure (stops), then the tone mapper, then sRGB: a display colour with
/// channels in [0, 1]. Non-finite or negative input gives black.
pub fn display_color(radiance: Vec3, exposure: f32, tonemap: u32) -> Vec3 {
    let scaled = (radiance * exposure.exp2()).max(Vec3::ZERO);
    let mapped = if tonemap == TONEMAP_ACES {
        aces_filmic(scaled)
    } else {
        scaled.min(Vec3::ONE)
    };
    Vec3::new(
        srgb_encode(mapped.x),
        srgb_encode(mapped.y),
        srgb_encode(mapped.z),
    )
}

/// Packs a colour in [0, 1] as RGBA8 (red in the low byte, alpha 255), the
/// byte order of `Rgba8Unorm` and of PNG's RGBA.
pub fn pack_rgba8(c: Vec3) -> u32 {
    quantize(c.x) | (quantize(c.y) << 8) | (quantize(c.z) << 16) | (255 << 24)
}

/// [0, 1] to 0..=255, rounded to nearest. NaN fails both comparisons: 0.
fn quantize(v: f32) -> u32 {
    let v = if v > 0.0 {
        if v < 1.0 { v } else { 1.0 }
    } else {
        0.0
    };
    (v * 255.0 + 0.5) as u32
}
