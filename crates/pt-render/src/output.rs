//! Image files: PNG (display colours) and EXR (linear mean radiance),
//! written to a temporary file and renamed, so a failure leaves nothing.

use std::path::{Path, PathBuf};

use pt_core::AccumPixel;

/// Errors writing an image.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The extension is none of `.png`, `.exr` and `.ptpart`.
    #[error(
        "{0}: unsupported output format: use a .png (tone-mapped sRGB) or .exr (linear radiance) file name, \
         or .ptpart for a part of a split render"
    )]
    Format(PathBuf),
    /// The file or its folder cannot be written.
    #[error("{path}: cannot write the output file: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the OS said.
        source: std::io::Error,
    },
    /// The pixel data does not match the image size.
    #[error("{path}: {got} pixel values for a {width}x{height} image")]
    Size {
        /// The file.
        path: PathBuf,
        /// Width asked for.
        width: u32,
        /// Height asked for.
        height: u32,
        /// Values given.
        got: usize,
    },
    /// The encoder failed.
    #[error("{path}: cannot encode the image: {source}")]
    Encode {
        /// The file.
        path: PathBuf,
        /// The encoder's reason.
        source: image::ImageError,
    },
}

/// What an output file holds.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    /// Tone-mapped sRGB, 8 bits.
    Png,
    /// Linear mean radiance, 32-bit float RGB.
    Exr,
    /// A part of a split render: per-pixel sums (`crate::parts`).
    Part,
}

/// The format an output path asks for, by extension.
pub fn output_format(path: &Path) -> Result<OutputFormat, OutputError> {
    match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("png") => Ok(OutputFormat::Png),
        Some("exr") => Ok(OutputFormat::Exr),
        Some(crate::parts::EXTENSION) => Ok(OutputFormat::Part),
        _ => Err(OutputError::Format(path.to_owned())),
    }
}

fn temp_path(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// Checks, before any rendering, that `path` has a known format and that its
/// folder takes a new file: a long render never ends in "cannot write".
pub fn check_writable(path: &Path) -> Result<OutputFormat, OutputError> {
    let format = output_format(path)?;
    if path.is_dir() {
        return Err(OutputError::Io { path: path.to_owned(), source: std::io::Error::other("is a directory") });
    }
    let probe = temp_path(path);
    std::fs::write(&probe, b"").map_err(|source| OutputError::Io { path: path.to_owned(), source })?;
    let _ = std::fs::remove_file(&probe);
    Ok(format)
}

/// Writes `path` atomically: encode into a temporary sibling, then rename.
pub(crate) fn write_atomic(
    path: &Path,
    save: impl FnOnce(&Path) -> Result<(), image::ImageError>,
) -> Result<(), OutputError> {
    let tmp = temp_path(path);
    if let Err(source) = save(&tmp) {
        let _ = std::fs::remove_file(&tmp);
        return Err(match source {
            image::ImageError::IoError(source) => OutputError::Io { path: path.to_owned(), source },
            source => OutputError::Encode { path: path.to_owned(), source },
        });
    }
    std::fs::rename(&tmp, path).map_err(|source| {
        let _ = std::fs::remove_file(&tmp);
        OutputError::Io { path: path.to_owned(), source }
    })
}

/// Writes packed RGBA8 display pixels (row 0 at the top) as PNG.
pub fn write_png(path: &Path, width: u32, height: u32, rgba: &[u32]) -> Result<(), OutputError> {
    let bytes: Vec<u8> = bytemuck::cast_slice(rgba).to_vec();
    let got = rgba.len();
    let img = image::RgbaImage::from_raw(width, height, bytes).ok_or(OutputError::Size {
        path: path.to_owned(),
        width,
        height,
        got,
    })?;
    write_atomic(path, |p| img.save_with_format(p, image::ImageFormat::Png))
}

/// Mean radiance per pixel, linear RGB, row-major from the top.
pub fn mean_radiance(accum: &[AccumPixel]) -> Vec<[f32; 3]> {
    accum.iter().map(|p| p.mean().to_array()).collect()
}

/// Writes linear mean radiance (row 0 at the top) as 32-bit float EXR.
pub fn write_exr(path: &Path, width: u32, height: u32, rgb: &[[f32; 3]]) -> Result<(), OutputError> {
    let data: Vec<f32> = rgb.iter().flatten().copied().collect();
    let got = rgb.len();
    let img = image::Rgb32FImage::from_raw(width, height, data).ok_or(OutputError::Size {
        path: path.to_owned(),
        width,
        height,
        got,
    })?;
    write_atomic(path, |p| img.save_with_format(p, image::ImageFormat::OpenExr))
}

/// A PNG file's bytes of packed RGBA8 display pixels (row 0 at the top),
/// for outputs that are not files (the browser viewer's download).
pub fn encode_png(width: u32, height: u32, rgba: &[u32]) -> image::ImageResult<Vec<u8>> {
    if rgba.len() as u64 != width as u64 * height as u64 {
        return Err(size_mismatch());
    }
    let img =
        image::RgbaImage::from_raw(width, height, bytemuck::cast_slice(rgba).to_vec()).ok_or_else(size_mismatch)?;
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png)?;
    Ok(bytes.into_inner())
}

/// An EXR file's bytes of linear mean radiance (row 0 at the top).
pub fn encode_exr(width: u32, height: u32, rgb: &[[f32; 3]]) -> image::ImageResult<Vec<u8>> {
    if rgb.len() as u64 != width as u64 * height as u64 {
        return Err(size_mismatch());
    }
    let data: Vec<f32> = rgb.iter().flatten().copied().collect();
    let img = image::Rgb32FImage::from_raw(width, height, data).ok_or_else(size_mismatch)?;
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::OpenExr)?;
    Ok(bytes.into_inner())
}

fn size_mismatch() -> image::ImageError {
    image::ImageError::Parameter(image::error::ParameterError::from_kind(
        image::error::ParameterErrorKind::DimensionMismatch,
    ))
}

/// Reads an EXR's RGB as linear f32, row-major from the top.
pub fn read_exr(path: &Path) -> Result<(u32, u32, Vec<[f32; 3]>), image::ImageError> {
    let img = image::open(path)?.into_rgb32f();
    let (w, h) = img.dimensions();
    Ok((w, h, img.pixels().map(|p| p.0).collect()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn encoded_files_decode_to_the_pixels() {
        // The browser viewer's downloads: bytes, not files.
        let rgba = [0xff00_00ffu32, 0x8000_ff00, 0x0000_0000, 0xffff_ffff, 0x1234_5678, 0x0102_0304];
        let png = image::load_from_memory(&encode_png(3, 2, &rgba).unwrap()).unwrap().into_rgba8();
        assert_eq!(png.dimensions(), (3, 2));
        assert_eq!(png.as_raw().as_slice(), bytemuck::cast_slice::<u32, u8>(&rgba));

        let rgb = [[0.0, 1.5, -2.0], [1e-3, 1e3, 0.25]];
        let exr = image::load_from_memory(&encode_exr(1, 2, &rgb).unwrap()).unwrap().into_rgb32f();
        assert_eq!(exr.dimensions(), (1, 2));
        assert_eq!(exr.pixels().map(|p| p.0).collect::<Vec<_>>(), rgb);

        assert!(encode_png(2, 2, &rgba).is_err(), "6 pixels are not 2x2");
        assert!(encode_exr(2, 2, &rgb).is_err(), "2 pixels are not 2x2");
    }

    #[test]
    fn mismatched_pixel_count_is_an_error_and_writes_nothing() {
        let dir = std::env::temp_dir().join(format!("pt-output-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let png = dir.join("x.png");
        assert!(matches!(write_png(&png, 4, 4, &[0; 15]), Err(OutputError::Size { got: 15, .. })));
        let exr = dir.join("x.exr");
        assert!(matches!(write_exr(&exr, 2, 2, &[[0.0; 3]; 3]), Err(OutputError::Size { got: 3, .. })));
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0, "a file was left behind");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn exr_round_trips_linear_radiance() {
        let dir = std::env::temp_dir().join(format!("pt-output-exr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("r.exr");
        let px = [[0.25, 20.0, 1e-3], [0.0, 1.5, 7.0]];
        write_exr(&path, 2, 1, &px).unwrap();
        let (w, h, back) = read_exr(&path).unwrap();
        assert_eq!((w, h), (2, 1));
        assert_eq!(back, px.to_vec());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
