//! The chi-square distribution and a Mitsuba-style binned goodness-of-fit
//! test for direction samplers, for the sampling routines' tests.

use std::f64::consts::PI;

/// ln Gamma(x), Lanczos approximation (g = 7, n = 9), accurate to ~1e-15.
pub fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let t = x + 7.5;
    let mut a = C[0];
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularised upper incomplete gamma Q(a, x) (Numerical Recipes 6.2:
/// series below a + 1, continued fraction above).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let gln = ln_gamma(a);
    if x < a + 1.0 {
        let (mut sum, mut del, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * (-x + a * x.ln() - gln).exp()
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        (-x + a * x.ln() - gln).exp() * h
    }
}

/// P(X >= chi2) for a chi-square variable with `dof` degrees of freedom.
pub fn chi2_p_value(chi2: f64, dof: usize) -> f64 {
    gamma_q(dof as f64 / 2.0, chi2 / 2.0)
}

/// Result of a binned goodness-of-fit test.
#[derive(Clone, Debug)]
pub struct Chi2Result {
    /// The statistic after pooling.
    pub chi2: f64,
    /// Degrees of freedom after pooling.
    pub dof: usize,
    /// P-value of the statistic.
    pub p_value: f64,
}

/// Chi-square test of observed against expected counts, pooling cells
/// whose expected count is below 5 into one (as Mitsuba 3's `chi2.py`).
pub fn chi2_test(observed: &[f64], expected: &[f64]) -> Chi2Result {
    let (mut chi2, mut dof) = (0.0, 0usize);
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    for (&o, &e) in observed.iter().zip(expected) {
        if e < 5.0 {
            pool_o += o;
            pool_e += e;
        } else {
            chi2 += (o - e) * (o - e) / e;
            dof += 1;
        }
    }
    if pool_e > 0.0 {
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        dof += 1;
    }
    let dof = dof.saturating_sub(1).max(1);
    Chi2Result { chi2, dof, p_value: chi2_p_value(chi2, dof) }
}

/// Bins of a (cos theta, phi) grid over the whole sphere: `nt` bands of
/// equal cos theta in [-1, 1] and `np` sectors of phi. Equal-area cells.
pub struct SphereBins {
    /// Bands in cos theta.
    pub nt: usize,
    /// Sectors in phi.
    pub np: usize,
}

impl SphereBins {
    /// The cell of unit direction `d`.
    pub fn cell(&self, d: [f64; 3]) -> usize {
        let t = (((d[2] + 1.0) * 0.5 * self.nt as f64) as usize).min(self.nt - 1);
        let phi = d[1].atan2(d[0]).rem_euclid(2.0 * PI);
        let p = ((phi / (2.0 * PI) * self.np as f64) as usize).min(self.np - 1);
        t * self.np + p
    }

    /// Expected counts for `n` samples of the solid-angle density `pdf`,
    /// each cell's integral by a `sub` x `sub` midpoint rule.
    pub fn expected(&self, n: usize, sub: usize, pdf: impl Fn([f64; 3]) -> f64) -> Vec<f64> {
        let mut out = vec![0.0; self.nt * self.np];
        let dz = 2.0 / self.nt as f64;
        let dphi = 2.0 * PI / self.np as f64;
        for t in 0..self.nt {
            for p in 0..self.np {
                let mut integral = 0.0;
                for i in 0..sub {
                    for j in 0..sub {
                        let z = -1.0 + dz * (t as f64 + (i as f64 + 0.5) / sub as f64);
                        let phi = dphi * (p as f64 + (j as f64 + 0.5) / sub as f64);
                        let r = (1.0 - z * z).max(0.0).sqrt();
                        integral += pdf([r * phi.cos(), r * phi.sin(), z]);
                    }
                }
                // d(solid angle) = dz dphi on the sphere.
                out[t * self.np + p] = integral * dz * dphi / (sub * sub) as f64 * n as f64;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chi2_p_values_match_tables() {
        // Known quantiles: P(chi2_1 >= 3.841) = 0.05, P(chi2_10 >= 18.307) = 0.05,
        // P(chi2_50 >= 76.154) = 0.01.
        assert!((chi2_p_value(3.841_458_8, 1) - 0.05).abs() < 1e-6);
        assert!((chi2_p_value(18.307_038, 10) - 0.05).abs() < 1e-6);
        assert!((chi2_p_value(76.153_891, 50) - 0.01).abs() < 1e-6);
    }

    #[test]
    fn ln_gamma_of_integers_is_log_factorial() {
        assert!((ln_gamma(1.0)).abs() < 1e-12);
        assert!((ln_gamma(5.0) - 24f64.ln()).abs() < 1e-12);
        assert!((ln_gamma(0.5) - PI.sqrt().ln()).abs() < 1e-12);
    }

    #[test]
    fn uniform_sphere_density_gives_equal_cells() {
        let bins = SphereBins { nt: 4, np: 8 };
        let e = bins.expected(3200, 4, |_| 1.0 / (4.0 * PI));
        assert!(e.iter().all(|&x| (x - 100.0).abs() < 1e-9));
    }
}
