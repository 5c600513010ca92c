//! `pathtracer merge`: the parts of a split render joined into its image.

use anyhow::{Context, Result};
use pt_core::tonemap::{display_color, pack_rgba8};
use pt_render::output::{self, OutputFormat};
use pt_render::parts;

use crate::MergeArgs;

/// Reads every part, checks that they are parts of one render that cover
/// its samples once, and writes the image; nothing is written on error.
pub(crate) fn run(args: &MergeArgs) -> Result<()> {
    if !args.exposure.is_finite() {
        anyhow::bail!("--exposure must be a finite number");
    }
    let format = output::check_writable(&args.out)?;
    if format == OutputFormat::Part {
        anyhow::bail!("{}: merge writes the image, a .png or .exr file", args.out.display());
    }
    let (header, accum) = parts::merge(&args.parts).context("cannot merge")?;
    match format {
        OutputFormat::Png => {
            let tonemap = args.tonemap.code();
            let rgba: Vec<u32> =
                accum.iter().map(|p| pack_rgba8(display_color(p.mean(), args.exposure, tonemap))).collect();
            output::write_png(&args.out, header.width, header.height, &rgba)?;
        }
        _ => output::write_exr(&args.out, header.width, header.height, &output::mean_radiance(&accum))?,
    }
    let non_finite: u64 = accum.iter().map(|p| p.non_finite as u64).sum();
    println!(
        "merged {} parts: {}x{}, {} spp, {non_finite} non-finite samples",
        args.parts.len(),
        header.width,
        header.height,
        header.spp
    );
    println!("wrote {}", args.out.display());
    Ok(())
}
