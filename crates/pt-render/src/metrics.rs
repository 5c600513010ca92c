//! Error metrics (docs/ARCHITECTURE.md, Conventions), and region statistics for tests.

/// Mean over pixels and channels of `f(image, reference)`, in f64.
fn mean_over(image: &[[f32; 3]], reference: &[[f32; 3]], f: impl Fn(f64, f64) -> f64) -> f64 {
    assert_eq!(image.len(), reference.len(), "images of different sizes");
    let mut sum = 0.0;
    for (a, b) in image.iter().zip(reference) {
        for c in 0..3 {
            sum += f(a[c] as f64, b[c] as f64);
        }
    }
    sum / (3 * image.len().max(1)) as f64
}

/// Mean squared error.
pub fn mse(image: &[[f32; 3]], reference: &[[f32; 3]]) -> f64 {
    mean_over(image, reference, |i, r| (i - r) * (i - r))
}

/// Root mean squared error.
pub fn rmse(image: &[[f32; 3]], reference: &[[f32; 3]]) -> f64 {
    mse(image, reference).sqrt()
}

/// What the relative metrics add to the reference's value, so that black
/// pixels do not divide by zero.
pub const REL_EPSILON: f64 = 0.01;

/// Relative MSE: mean((I - R)^2 / (R^2 + 0.01)).
pub fn rel_mse(image: &[[f32; 3]], reference: &[[f32; 3]]) -> f64 {
    mean_over(image, reference, |i, r| (i - r) * (i - r) / (r * r + REL_EPSILON))
}

/// Mean absolute percentage error: mean(|I - R| / (R + 0.01)).
pub fn mape(image: &[[f32; 3]], reference: &[[f32; 3]]) -> f64 {
    mean_over(image, reference, |i, r| (i - r).abs() / (r + REL_EPSILON))
}

/// Mean radiance of each `block` x `block` region, row-major over regions
/// (partial regions at the right and bottom edges included).
pub fn region_means(image: &[[f32; 3]], width: u32, height: u32, block: u32) -> Vec<[f64; 3]> {
    let (w, h, b) = (width as usize, height as usize, block as usize);
    let (rx, ry) = (w.div_ceil(b), h.div_ceil(b));
    let mut sums = vec![[0.0f64; 3]; rx * ry];
    let mut counts = vec![0usize; rx * ry];
    for y in 0..h {
        for x in 0..w {
            let r = (y / b) * rx + x / b;
            for c in 0..3 {
                sums[r][c] += image[y * w + x][c] as f64;
            }
            counts[r] += 1;
        }
    }
    sums.iter().zip(&counts).map(|(s, &n)| s.map(|v| v / n as f64)).collect()
}

/// The paired t statistic of each `block` x `block` region and channel,
/// row-major over regions: the mean of the pixel differences `I - R` over
/// their standard error. When both images are unbiased estimates of the
/// same image from independent samples, each is close to a standard
/// normal draw (regions of a few hundred pixels); a bias shows as a large
/// value. A region whose pixels agree exactly has statistic 0; one whose
/// differences are all equal but not zero has an infinite statistic.
pub fn region_t_statistics(
    image: &[[f32; 3]],
    reference: &[[f32; 3]],
    width: u32,
    height: u32,
    block: u32,
) -> Vec<[f64; 3]> {
    let (w, h, b) = (width as usize, height as usize, block as usize);
    let (rx, ry) = (w.div_ceil(b), h.div_ceil(b));
    let mut diffs = vec![[const { Vec::new() }; 3]; rx * ry];
    for y in 0..h {
        for x in 0..w {
            let (i, r) = (image[y * w + x], reference[y * w + x]);
            for c in 0..3 {
                diffs[(y / b) * rx + x / b][c].push(i[c] as f64 - r[c] as f64);
            }
        }
    }
    diffs
        .iter()
        .map(|region| {
            region.each_ref().map(|d| {
                let (mean, stderr) = mean_and_stderr(d);
                match (mean == 0.0, stderr > 0.0) {
                    (true, _) => 0.0,
                    (false, true) => mean / stderr,
                    (false, false) => mean.signum() * f64::INFINITY,
                }
            })
        })
        .collect()
}

/// Mean and standard error of the mean of independent estimates.
pub fn mean_and_stderr(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, (var / n).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn t_statistics_are_exact_on_known_differences() {
        // One 2x1 region: differences (1, 3) in red: mean 2, sample
        // standard deviation sqrt(2), standard error 1, t = 2. Green
        // agrees exactly (0); blue differs by 1 everywhere (infinite).
        let r = [[0.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let i = [[1.0, 1.0, 1.0], [3.0, 1.0, 1.0]];
        let t = region_t_statistics(&i, &r, 2, 1, 2);
        assert_eq!(t.len(), 1);
        assert!((t[0][0] - 2.0).abs() < 1e-12, "{t:?}");
        assert_eq!(t[0][1], 0.0);
        assert_eq!(t[0][2], f64::INFINITY);
        // Blocks of 1: each region has one pixel, no spread.
        assert_eq!(region_t_statistics(&i, &r, 2, 1, 1).len(), 2);
    }

    #[test]
    fn metrics_match_hand_computed_values() {
        let r = [[1.0, 0.0, 2.0]];
        let i = [[1.5, 0.1, 2.0]];
        // squared errors 0.25, 0.01, 0
        assert!((mse(&i, &r) - 0.26 / 3.0).abs() < 1e-7);
        let rel = (0.25 / 1.01 + 0.01 / 0.01 + 0.0) / 3.0;
        assert!((rel_mse(&i, &r) - rel).abs() < 1e-7);
        let ape = (0.5 / 1.01 + 0.1 / 0.01 + 0.0) / 3.0;
        assert!((mape(&i, &r) - ape).abs() < 1e-6);
    }

    #[test]
    fn region_means_average_each_block() {
        // 3x2 image, blocks of 2: regions (0..2, 0..2) and (2..3, 0..2).
        let img: Vec<[f32; 3]> = (0..6).map(|v| [v as f32; 3]).collect();
        let m = region_means(&img, 3, 2, 2);
        assert_eq!(m.len(), 2);
        assert_eq!(m[0][0], (0.0 + 1.0 + 3.0 + 4.0) / 4.0);
        assert_eq!(m[1][0], (2.0 + 5.0) / 2.0);
    }

    #[test]
    fn stderr_of_known_sample() {
        let (m, se) = mean_and_stderr(&[1.0, 2.0, 3.0, 4.0]);
        assert_eq!(m, 2.5);
        // sample variance 5/3, se = sqrt(5/12)
        assert!((se - (5.0f64 / 12.0).sqrt()).abs() < 1e-12);
    }
}
