//! `pathtracer compare`: an EXR against a reference EXR.

use std::path::PathBuf;

use anyhow::{Context, Result};
use pt_render::{metrics, output};

use crate::CompareArgs;

/// Relative difference of region means below which `--max-t` passes a
/// region whatever its t statistic.
const REL_TOL: f64 = 1e-4;

/// Prints the error metrics of an image against a reference.
pub(crate) fn run(args: &CompareArgs) -> Result<()> {
    let read = |p: &PathBuf| output::read_exr(p).with_context(|| format!("{}: cannot read the EXR", p.display()));
    let (w, h, image) = read(&args.image)?;
    let (rw, rh, reference) = read(&args.reference)?;
    if (w, h) != (rw, rh) {
        anyhow::bail!(
            "{} is {w}x{h} but the reference {} is {rw}x{rh}",
            args.image.display(),
            args.reference.display()
        );
    }
    println!("MSE     {:.6e}", metrics::mse(&image, &reference));
    println!("RMSE    {:.6e}", metrics::rmse(&image, &reference));
    println!("relMSE  {:.6e}", metrics::rel_mse(&image, &reference));
    println!("MAPE    {:.6e}", metrics::mape(&image, &reference));
    // Region means: bias shows as a region that differs beyond the noise.
    let a = metrics::region_means(&image, w, h, args.block);
    let b = metrics::region_means(&reference, w, h, args.block);
    let mut worst = (0.0f64, 0usize, 0usize);
    let mut sum_rel = 0.0;
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        for c in 0..3 {
            let rel = (x[c] - y[c]) / (y[c].abs() + 0.01);
            sum_rel += rel;
            if rel.abs() > worst.0.abs() {
                worst = (rel, i, c);
            }
        }
    }
    let regions_x = w.div_ceil(args.block) as usize;
    println!(
        "regions of {0}x{0}: mean relative difference {1:+.4e}, largest {2:+.4e} (region x {3}, y {4}, channel {5})",
        args.block,
        sum_rel / (3 * a.len()) as f64,
        worst.0,
        worst.1 % regions_x,
        worst.1 / regions_x,
        ["r", "g", "b"][worst.2]
    );
    if let Some(max_t) = args.max_t {
        let t = metrics::region_t_statistics(&image, &reference, w, h, args.block);
        // A region whose means agree to a relative 1e-4 passes whatever its
        // t: where both images are noiseless (a light seen directly) the
        // standard error is 0 and any rounding difference, such as another
        // renderer's handling of an emitter's RGB radiance (1e-5 relative
        // in Mitsuba 3), would have an infinite t.
        let close = |i: usize, c: usize| (a[i][c] - b[i][c]).abs() <= REL_TOL * (b[i][c].abs() + 0.01);
        let (i, c, worst) = t
            .iter()
            .enumerate()
            .flat_map(|(i, r)| (0..3).map(move |c| (i, c, r[c])))
            .map(|(i, c, v)| (i, c, if close(i, c) { 0.0 } else { v }))
            .max_by(|a, b| a.2.abs().total_cmp(&b.2.abs()))
            .context("empty image")?;
        let at = format!("region x {}, y {}, channel {}", i % regions_x, i / regions_x, ["r", "g", "b"][c]);
        println!("paired t over {} regions: largest |t| {:.3} ({at}), allowed {max_t}", t.len(), worst.abs());
        if worst.abs() > max_t {
            anyhow::bail!(
                "{} differs from {} beyond the noise: |t| = {:.3} > {max_t} at {at}",
                args.image.display(),
                args.reference.display(),
                worst.abs()
            );
        }
    }
    Ok(())
}
