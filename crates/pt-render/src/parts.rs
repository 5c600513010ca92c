//! Split renders: one render cut into parts by sample range, each part a
//! file of per-pixel sums, and the merge of the parts into the image a
//! single render makes.
//!
//! Part `k` of `n` takes a range of the render's frames, so its samples are
//! those the single render draws in those frames: the same Sobol indices
//! and PCG streams, and Sobol stratification survives the split (parts by
//! seed would not have it). A merged image differs from the single render
//! only by the order of the float sums.
//!
//! # The part file (`.ptpart`)
//!
//! All little-endian:
//! - the 8 bytes `PTPART1\n`;
//! - a u32, the length of the header in bytes, then the header: TOML with
//!   `render` (SHA-256 of the scene and every setting that changes the
//!   expected image or the sample streams, hex), `width`, `height`, `spp`
//!   (of the whole render), `first_sample` and `end_sample` (this part's
//!   samples per pixel, a half-open range), `part` and `parts`;
//! - `width * height` pixels, row 0 at the top, each 32 bytes: the sum of
//!   its samples' radiance (3 x f32), the number of samples (u32), the
//!   Kahan compensation of the sum (3 x f32) and the number of non-finite
//!   samples discarded (u32), as the accumulation buffer holds them.

use std::io::Read as _;
use std::ops::Range;
use std::path::{Path, PathBuf};

use pt_core::AccumPixel;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::output::{OutputError, write_atomic};
use crate::scene::{RenderSettings, Scene};

/// The first bytes of a part file.
const MAGIC: &[u8; 8] = b"PTPART1\n";

/// The file extension of parts.
pub const EXTENSION: &str = "ptpart";

/// Errors of reading, checking and merging parts.
#[derive(Debug, thiserror::Error)]
pub enum PartError {
    /// The file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The reason.
        source: std::io::Error,
    },
    /// The file is not a part, or is cut short.
    #[error("{path}: not a pathtracer part file ({reason})")]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// Parts of different renders.
    #[error(
        "{path} is a part of another render than {first} ({what}); merge only parts made with the same scene and settings"
    )]
    Mismatch {
        /// The odd part.
        path: PathBuf,
        /// The first part given.
        first: PathBuf,
        /// What differs.
        what: String,
    },
    /// Samples no part covers, or covered twice.
    #[error("the parts do not cover samples 0..{spp} exactly once: {problems}")]
    Coverage {
        /// Samples per pixel of the whole render.
        spp: u32,
        /// Each missing or overlapping range, with the parts involved.
        problems: String,
    },
    /// No part was given.
    #[error("no part files given")]
    Empty,
}

/// The samples per pixel of part `part` (from 0) of `parts`: a range of
/// whole frames of `per_frame` samples, the frames shared out as evenly as
/// they go. The ranges of all parts cover `0..spp` once, in order.
pub fn part_samples(spp: u32, per_frame: u32, part: u32, parts: u32) -> Range<u32> {
    let per_frame = per_frame.max(1) as u64;
    let frames = (spp as u64).div_ceil(per_frame);
    let edge = |k: u32| ((k as u64 * frames / parts.max(1) as u64) * per_frame).min(spp as u64) as u32;
    edge(part)..edge(part + 1)
}

/// What identifies a render: the scene and every setting that changes its
/// expected image or its sample streams, hashed. Parts merge only with
/// parts of the same render.
pub fn render_hash(scene: &Scene, settings: &RenderSettings, seed: u32, per_frame: u32, flags: u32) -> String {
    let text = format!(
        "{}\nwidth={} height={} spp={} max_bounces={} rr_start={} seed={seed} per_frame={per_frame} flags={flags}",
        scene.to_toml(),
        settings.width,
        settings.height,
        settings.spp,
        settings.max_bounces,
        settings.rr_start
    );
    Sha256::digest(text.as_bytes()).iter().map(|b| format!("{b:02x}")).collect()
}

/// The header of a part file.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartHeader {
    /// [`render_hash`] of the render this is a part of.
    pub render: String,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Samples per pixel of the whole render.
    pub spp: u32,
    /// This part's first sample per pixel.
    pub first_sample: u32,
    /// One past its last.
    pub end_sample: u32,
    /// Its index, from 0.
    pub part: u32,
    /// The number of parts it was cut into.
    pub parts: u32,
}

/// A part read from its file.
#[derive(Debug)]
pub struct Part {
    /// Where it was read from.
    pub path: PathBuf,
    /// Its header.
    pub header: PartHeader,
    /// Its pixels.
    pub accum: Vec<AccumPixel>,
}

/// Writes a part, atomically as every output file: a part that exists is
/// whole.
pub fn write_part(path: &Path, header: &PartHeader, accum: &[AccumPixel]) -> Result<(), OutputError> {
    let text = toml::to_string(header).expect("a part header serialises");
    let mut bytes = Vec::with_capacity(12 + text.len() + std::mem::size_of_val(accum));
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&(text.len() as u32).to_le_bytes());
    bytes.extend_from_slice(text.as_bytes());
    bytes.extend_from_slice(bytemuck::cast_slice(accum));
    write_atomic(path, |tmp| std::fs::write(tmp, &bytes).map_err(image::ImageError::IoError))
}

/// Reads a part file's header without its pixels, checking that the file
/// holds exactly the pixels the header says; returns the header and the
/// pixels' offset in the file.
pub fn read_header(path: &Path) -> Result<(PartHeader, u64), PartError> {
    let io = |source| PartError::Io { path: path.to_path_buf(), source };
    let bad = |reason: &str| PartError::Format { path: path.to_path_buf(), reason: reason.to_string() };
    let mut file = std::fs::File::open(path).map_err(io)?;
    let mut start = [0u8; 12];
    file.read_exact(&mut start).map_err(|_| bad("wrong magic bytes"))?;
    let (magic, len) = start.split_at(8);
    if magic != MAGIC {
        return Err(bad("wrong magic bytes"));
    }
    let len = u32::from_le_bytes(len.try_into().expect("4 bytes")) as u64;
    let mut text = Vec::new();
    (&mut file).take(len).read_to_end(&mut text).map_err(io)?;
    if text.len() as u64 != len {
        return Err(bad("header cut short"));
    }
    let text = std::str::from_utf8(&text).map_err(|_| bad("header is not UTF-8"))?;
    let header: PartHeader = toml::from_str(text).map_err(|e| bad(&format!("header: {e}")))?;
    let pixels = file.metadata().map_err(io)?.len().saturating_sub(12 + len);
    let expected = header.width as u64 * header.height as u64 * size_of::<AccumPixel>() as u64;
    if pixels != expected {
        return Err(bad(&format!(
            "{pixels} bytes of pixels for {}x{}, expected {expected}",
            header.width, header.height
        )));
    }
    Ok((header, 12 + len))
}

/// Reads a part file, header and pixels.
pub fn read_part(path: &Path) -> Result<Part, PartError> {
    let (header, offset) = read_header(path)?;
    let bytes = std::fs::read(path).map_err(|source| PartError::Io { path: path.to_path_buf(), source })?;
    let accum = bytemuck::pod_collect_to_vec(&bytes[offset as usize..]);
    Ok(Part { path: path.to_path_buf(), header, accum })
}

/// Checks that `parts` (file, header) belong to one render and cover its
/// samples exactly once; names every foreign part, and every range of
/// samples missing or covered twice. Returns the render's header.
pub fn check(parts: &[(PathBuf, PartHeader)]) -> Result<PartHeader, PartError> {
    let (path0, h0) = parts.first().ok_or(PartError::Empty)?;
    for (path, h) in &parts[1..] {
        let what = if h.render != h0.render {
            Some("scene or settings".to_string())
        } else if (h.width, h.height, h.spp) != (h0.width, h0.height, h0.spp) {
            Some(format!(
                "{}x{} at {} spp against {}x{} at {} spp",
                h.width, h.height, h.spp, h0.width, h0.height, h0.spp
            ))
        } else {
            None
        };
        if let Some(what) = what {
            return Err(PartError::Mismatch { path: path.clone(), first: path0.clone(), what });
        }
    }

    let mut ranges: Vec<(Range<u32>, &Path)> =
        parts.iter().map(|(path, h)| (h.first_sample..h.end_sample, path.as_path())).collect();
    ranges.sort_by_key(|(r, _)| (r.start, r.end));
    let mut problems = Vec::new();
    let mut covered = 0u32;
    let mut last: Option<&Path> = None;
    for (r, path) in &ranges {
        if r.start > covered {
            problems.push(format!("samples {covered}..{} missing", r.start));
        } else if r.start < covered {
            let by = last.map_or(String::new(), |l| format!(" by {} and {}", l.display(), path.display()));
            problems.push(format!("samples {}..{} covered twice{by}", r.start, covered.min(r.end)));
        }
        covered = covered.max(r.end);
        last = Some(path);
    }
    if covered < h0.spp {
        problems.push(format!("samples {covered}..{} missing", h0.spp));
    }
    if !problems.is_empty() {
        return Err(PartError::Coverage { spp: h0.spp, problems: problems.join("; ") });
    }
    Ok(PartHeader { first_sample: 0, end_sample: h0.spp, part: 0, parts: 1, ..h0.clone() })
}

/// Merges the part files `paths`, given in any order, into the
/// accumulation of the whole render: every header is [`check`]ed first,
/// then the parts are read one at a time (memory holds one part and the
/// sums) and their per-pixel sums added in f64, rounded once at the end.
pub fn merge(paths: &[PathBuf]) -> Result<(PartHeader, Vec<AccumPixel>), PartError> {
    let headers: Vec<(PathBuf, PartHeader)> =
        paths.iter().map(|p| read_header(p).map(|(h, _)| (p.clone(), h))).collect::<Result<_, _>>()?;
    let header = check(&headers)?;
    let pixels = header.width as usize * header.height as usize;
    let mut sums = vec![[0f64; 3]; pixels];
    let mut merged = vec![AccumPixel::default(); pixels];
    for path in paths {
        let part = read_part(path)?;
        for ((sum, m), a) in sums.iter_mut().zip(&mut merged).zip(&part.accum) {
            // The compensation holds the low part lost from `sum`, negated.
            let exact = a.sum.as_dvec3() - a.compensation.as_dvec3();
            for c in 0..3 {
                sum[c] += exact[c];
            }
            m.samples += a.samples;
            m.non_finite += a.non_finite;
        }
    }
    for (m, s) in merged.iter_mut().zip(&sums) {
        m.sum = pt_core::glam::DVec3::from_array(*s).as_vec3();
    }
    Ok((header, merged))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Case: parts cover every sample once, in order, on frame boundaries;
    /// more parts than frames leaves some empty, never a gap.
    #[test]
    fn part_samples_cover_the_render_on_frame_boundaries() {
        for (spp, per_frame, parts) in [(4096, 64, 16), (1000, 64, 3), (100, 7, 8), (8, 64, 4), (64, 8, 8)] {
            let mut next = 0;
            for k in 0..parts {
                let r = part_samples(spp, per_frame, k, parts);
                assert_eq!(r.start, next, "{spp} spp, {per_frame}/frame, part {k} of {parts}");
                assert!(r.start.is_multiple_of(per_frame) || r.start == spp);
                next = r.end;
            }
            assert_eq!(next, spp);
        }
        assert_eq!(part_samples(4096, 64, 3, 16), 768..1024);
    }

    fn header(first: u32, end: u32, render: &str) -> PartHeader {
        PartHeader {
            render: render.into(),
            width: 2,
            height: 1,
            spp: 8,
            first_sample: first,
            end_sample: end,
            part: 0,
            parts: 2,
        }
    }

    fn named(first: u32, end: u32, render: &str) -> (PathBuf, PartHeader) {
        (PathBuf::from(format!("p{first}")), header(first, end, render))
    }

    /// Writes a part of the 2x1 image whose pixels sum `first` over
    /// `end - first` samples into `dir`.
    fn part_file(dir: &Path, first: u32, end: u32) -> PathBuf {
        let px =
            AccumPixel { sum: pt_core::glam::Vec3::splat(first as f32), samples: end - first, ..Default::default() };
        let path = dir.join(format!("p{first}.ptpart"));
        write_part(&path, &header(first, end, "a"), &[px; 2]).unwrap();
        path
    }

    /// Case: parts in any order add up; gaps, overlaps and foreign parts
    /// are named.
    #[test]
    fn merge_adds_parts_and_names_what_is_wrong() {
        let dir = std::env::temp_dir().join(format!("pt-merge-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (h, m) = merge(&[part_file(&dir, 4, 8), part_file(&dir, 0, 4)]).unwrap();
        assert_eq!((h.first_sample, h.end_sample), (0, 8));
        assert_eq!((m[0].sum.x, m[0].samples), (4.0, 8));
        std::fs::remove_dir_all(&dir).unwrap();
        let e = check(&[named(0, 2, "a"), named(4, 6, "a")]).unwrap_err().to_string();
        assert!(e.contains("samples 2..4 missing") && e.contains("samples 6..8 missing"), "{e}");
        let e = check(&[named(0, 6, "a"), named(4, 8, "a")]).unwrap_err().to_string();
        assert!(e.contains("samples 4..6 covered twice"), "{e}");
        let e = check(&[named(0, 4, "a"), named(4, 8, "b")]).unwrap_err().to_string();
        assert!(e.contains("p4 is a part of another render than p0"), "{e}");
        assert!(matches!(check(&[]), Err(PartError::Empty)));
    }

    /// Case: a part file reads back as written; a cut one is an error.
    #[test]
    fn part_files_round_trip_and_cut_ones_are_refused() {
        let dir = std::env::temp_dir().join(format!("pt-parts-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = part_file(&dir, 0, 4);
        let back = read_part(&path).unwrap();
        assert_eq!(back.header, header(0, 4, "a"));
        let px = AccumPixel { sum: pt_core::glam::Vec3::ZERO, samples: 4, ..Default::default() };
        assert_eq!(back.accum, [px; 2]);
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() - 1]).unwrap();
        assert!(read_part(&path).unwrap_err().to_string().contains("bytes of pixels"));
        std::fs::write(&path, b"PNG").unwrap();
        assert!(read_part(&path).unwrap_err().to_string().contains("wrong magic"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
