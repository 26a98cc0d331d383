//! Phase functions of the paper: Henyey–Greenstein (eq. 7) sampled by eq. 9, multi-lobe
//! HG (eq. 8), and HG plus an isotropic fraction f_d (eq. 10). One closed enum, matched in
//! the hot loop (no dynamic dispatch). All depend only on cos θ = d_old · d_new, the cosine
//! between the travel directions before and after scattering; values are per steradian.

use crate::error::{check_range, Error, Result};
use crate::math::{direction_about_cs, Vec3};
use std::f64::consts::PI;

const INV_4PI: f64 = 1.0 / (4.0 * PI);
/// Below this |g| a HG lobe is sampled as isotropic: eq. 9 divides by g.
const G_ISOTROPIC: f64 = 1e-6;
/// Most lobes a [`PhaseFunction::MultiLobe`] holds (fixed so the enum stays `Copy`).
pub const MAX_LOBES: usize = 4;

/// One HG lobe of eq. 8: weight ω_i and asymmetry g_i.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Lobe {
    /// Weight ω_i (the weights of a phase function sum to 1).
    pub weight: f64,
    /// Asymmetry g_i in (−1, 1).
    pub g: f64,
}

/// A phase function.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PhaseFunction {
    /// p = 1/(4π).
    Isotropic,
    /// Henyey–Greenstein, eq. 7.
    HenyeyGreenstein {
        /// Asymmetry g in (−1, 1): the mean cosine.
        g: f64,
    },
    /// Weighted sum of HG lobes, eq. 8.
    MultiLobe {
        /// Lobes; only the first `count` are used.
        lobes: [Lobe; MAX_LOBES],
        /// Number of lobes in use (1..=MAX_LOBES).
        count: usize,
    },
    /// f_d/(4π) + (1 − f_d)·HG(g), eq. 10 (Prahl's "modified HG").
    HgIsotropic {
        /// Asymmetry of the HG part, in (−1, 1).
        g: f64,
        /// Isotropic fraction f_d in [0, 1].
        fd: f64,
    },
}

/// Eq. 7 for one lobe.
#[inline]
fn hg(g: f64, cos_theta: f64) -> f64 {
    let denom = 1.0 + g * g - 2.0 * g * cos_theta;
    INV_4PI * (1.0 - g * g) / (denom * denom.sqrt())
}

/// Eq. 9: cos θ of a HG lobe from one uniform ξ in [0, 1).
#[inline]
pub fn sample_hg_cos(g: f64, xi: f64) -> f64 {
    if g.abs() < G_ISOTROPIC {
        return 1.0 - 2.0 * xi;
    }
    let frac = (1.0 - g * g) / (1.0 - g + 2.0 * g * xi);
    ((1.0 + g * g - frac * frac) / (2.0 * g)).clamp(-1.0, 1.0)
}

/// CDF of cos θ for one HG lobe, P(cos θ ≤ mu).
fn hg_cdf(g: f64, mu: f64) -> f64 {
    if g.abs() < G_ISOTROPIC {
        return 0.5 * (mu + 1.0);
    }
    let s = (1.0 + g * g - 2.0 * g * mu).sqrt();
    ((1.0 - g * g) / (2.0 * g) * (1.0 / s - 1.0 / (1.0 + g))).clamp(0.0, 1.0)
}

impl PhaseFunction {
    /// A medium's phase function from its parameters: multi-lobe HG (eq. 8) when `lobes`
    /// are given, else [`PhaseFunction::hg_with_isotropic`]; validated.
    pub fn from_params(g: f64, fd: f64, lobes: &[(f64, f64)]) -> Result<Self> {
        if lobes.is_empty() {
            Self::hg_with_isotropic(g, fd)
        } else {
            Self::multi_lobe(lobes)
        }
    }

    /// HG when `fd` is 0, HG + isotropic (eq. 10) otherwise; validated.
    pub fn hg_with_isotropic(g: f64, fd: f64) -> Result<Self> {
        check_range("g", g, -1.0, true, 1.0, true, "")?;
        check_range("fd", fd, 0.0, false, 1.0, false, "")?;
        Ok(if fd == 0.0 {
            PhaseFunction::HenyeyGreenstein { g }
        } else {
            PhaseFunction::HgIsotropic { g, fd }
        })
    }

    /// Multi-lobe HG (eq. 8) from (weight, g) pairs; weights must sum to 1.
    pub fn multi_lobe(pairs: &[(f64, f64)]) -> Result<Self> {
        if pairs.is_empty() || pairs.len() > MAX_LOBES {
            return Err(Error::InvalidInput(format!(
                "lobes: {} given, allowed 1..={MAX_LOBES}",
                pairs.len()
            )));
        }
        let mut lobes = [Lobe::default(); MAX_LOBES];
        for (i, &(w, g)) in pairs.iter().enumerate() {
            check_range(&format!("lobes[{i}].weight"), w, 0.0, false, 1.0, false, "")?;
            check_range(&format!("lobes[{i}].g"), g, -1.0, true, 1.0, true, "")?;
            lobes[i] = Lobe { weight: w, g };
        }
        let total: f64 = pairs.iter().map(|p| p.0).sum();
        if (total - 1.0).abs() > 1e-9 {
            return Err(Error::InvalidInput(format!(
                "lobes: weights sum to {total}, they must sum to 1"
            )));
        }
        Ok(PhaseFunction::MultiLobe {
            lobes,
            count: pairs.len(),
        })
    }

    /// Check the parameters of an already built phase function.
    pub fn validate(&self) -> Result<()> {
        match *self {
            PhaseFunction::Isotropic => Ok(()),
            PhaseFunction::HenyeyGreenstein { g } => check_range("g", g, -1.0, true, 1.0, true, ""),
            PhaseFunction::HgIsotropic { g, fd } => Self::hg_with_isotropic(g, fd).map(|_| ()),
            PhaseFunction::MultiLobe { lobes, count } => {
                let pairs: Vec<(f64, f64)> =
                    lobes.iter().take(count).map(|l| (l.weight, l.g)).collect();
                Self::multi_lobe(&pairs).map(|_| ())
            }
        }
    }

    /// p(cos θ) per steradian.
    #[inline]
    pub fn eval(&self, cos_theta: f64) -> f64 {
        match *self {
            PhaseFunction::Isotropic => INV_4PI,
            PhaseFunction::HenyeyGreenstein { g } => hg(g, cos_theta),
            PhaseFunction::HgIsotropic { g, fd } => fd * INV_4PI + (1.0 - fd) * hg(g, cos_theta),
            PhaseFunction::MultiLobe { lobes, count } => lobes[..count]
                .iter()
                .map(|l| l.weight * hg(l.g, cos_theta))
                .sum(),
        }
    }

    /// [`Self::eval`] of every cosine in `c`, in place, with the same numbers: the lobe
    /// kind is matched once, so the loop over the cosines vectorises.
    pub fn eval_in_place(&self, c: &mut [f64]) {
        match *self {
            PhaseFunction::HenyeyGreenstein { g } => c.iter_mut().for_each(|v| *v = hg(g, *v)),
            PhaseFunction::HgIsotropic { g, fd } => c
                .iter_mut()
                .for_each(|v| *v = fd * INV_4PI + (1.0 - fd) * hg(g, *v)),
            _ => c.iter_mut().for_each(|v| *v = self.eval(*v)),
        }
    }

    /// Sampling density of [`Self::sample`] per steradian: equal to `eval` (exact sampling).
    #[inline]
    pub fn pdf(&self, cos_theta: f64) -> f64 {
        self.eval(cos_theta)
    }

    /// Mean cosine ⟨cos θ⟩ (the effective g).
    pub fn mean_cosine(&self) -> f64 {
        match *self {
            PhaseFunction::Isotropic => 0.0,
            PhaseFunction::HenyeyGreenstein { g } => g,
            PhaseFunction::HgIsotropic { g, fd } => (1.0 - fd) * g,
            PhaseFunction::MultiLobe { lobes, count } => {
                lobes[..count].iter().map(|l| l.weight * l.g).sum()
            }
        }
    }

    /// Whether [`Self::sample_cos`] reads `u[1]` (the choice of lobe or of the isotropic
    /// part); a single-lobe function only needs `u[0]`, so a tracer can skip drawing `u[1]`.
    #[inline]
    pub fn uses_second_uniform(&self) -> bool {
        matches!(
            self,
            PhaseFunction::MultiLobe { .. } | PhaseFunction::HgIsotropic { .. }
        )
    }

    /// Sample cos θ from two uniforms: u[1] picks the lobe (or the isotropic part of
    /// eq. 10), u[0] gives cos θ inside it.
    #[inline]
    pub fn sample_cos(&self, u: [f64; 2]) -> f64 {
        match *self {
            PhaseFunction::Isotropic => 1.0 - 2.0 * u[0],
            PhaseFunction::HenyeyGreenstein { g } => sample_hg_cos(g, u[0]),
            PhaseFunction::HgIsotropic { g, fd } => {
                if u[1] < fd {
                    1.0 - 2.0 * u[0]
                } else {
                    sample_hg_cos(g, u[0])
                }
            }
            PhaseFunction::MultiLobe { lobes, count } => {
                // choose lobe i with probability ω_i by u[1], keep u[0] for its cos θ
                let mut acc = 0.0;
                let mut pick = count - 1;
                for (i, l) in lobes[..count].iter().enumerate() {
                    acc += l.weight;
                    if u[1] < acc {
                        pick = i;
                        break;
                    }
                }
                sample_hg_cos(lobes[pick].g, u[0])
            }
        }
    }

    /// New travel direction after scattering a photon travelling along `d`;
    /// `u` gives cos θ (see [`Self::sample_cos`]) and `azimuth` the uniform azimuth as
    /// (cos φ, sin φ) ([`crate::rng::Stream::azimuth`]).
    #[inline]
    pub fn sample(&self, d: Vec3, u: [f64; 2], azimuth: (f64, f64)) -> Vec3 {
        direction_about_cs(d, self.sample_cos(u), azimuth)
    }

    /// CDF of cos θ, P(cos θ ≤ mu): used by the chi-square tests.
    pub fn cdf_cos(&self, mu: f64) -> f64 {
        match *self {
            PhaseFunction::Isotropic => 0.5 * (mu + 1.0),
            PhaseFunction::HenyeyGreenstein { g } => hg_cdf(g, mu),
            PhaseFunction::HgIsotropic { g, fd } => {
                fd * 0.5 * (mu + 1.0) + (1.0 - fd) * hg_cdf(g, mu)
            }
            PhaseFunction::MultiLobe { lobes, count } => lobes[..count]
                .iter()
                .map(|l| l.weight * hg_cdf(l.g, mu))
                .sum(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Stream;

    fn cases() -> Vec<PhaseFunction> {
        vec![
            PhaseFunction::Isotropic,
            PhaseFunction::HenyeyGreenstein { g: 0.0 },
            PhaseFunction::HenyeyGreenstein { g: 0.75 },
            PhaseFunction::HenyeyGreenstein { g: -0.5 },
            PhaseFunction::HenyeyGreenstein { g: 0.96 },
            PhaseFunction::hg_with_isotropic(0.9, 0.2).unwrap(),
            PhaseFunction::multi_lobe(&[(0.7, 0.9), (0.3, -0.3)]).unwrap(),
        ]
    }

    /// ∫ p dω = 2π ∫ p(μ) dμ by composite Simpson on a fine grid in μ.
    #[test]
    fn pdf_integrates_to_one() {
        for p in cases() {
            let n = 200_000;
            let h = 2.0 / n as f64;
            let mut s = p.eval(-1.0) + p.eval(1.0);
            for i in 1..n {
                let mu = -1.0 + i as f64 * h;
                s += if i % 2 == 1 { 4.0 } else { 2.0 } * p.eval(mu);
            }
            let integral = 2.0 * PI * s * h / 3.0;
            assert!((integral - 1.0).abs() < 1e-6, "{p:?}: {integral}");
            assert!((p.cdf_cos(1.0) - 1.0).abs() < 1e-12);
            assert!(p.cdf_cos(-1.0).abs() < 1e-12);
            assert_eq!(p.pdf(0.3), p.eval(0.3));
        }
    }

    /// The slice form gives `eval`'s numbers, bit for bit (the layer kernel's sums rely on it).
    #[test]
    fn eval_in_place_is_eval() {
        let mut s = Stream::new(4, 0, 0);
        let cos: Vec<f64> = (0..1000).map(|_| 2.0 * s.uniform() - 1.0).collect();
        for p in cases() {
            let mut c = cos.clone();
            p.eval_in_place(&mut c);
            for (v, &mu) in c.iter().zip(&cos) {
                assert_eq!(v.to_bits(), p.eval(mu).to_bits(), "{p:?} at {mu}");
            }
        }
    }

    #[test]
    fn sampled_mean_cosine_is_g() {
        let mut s = Stream::new(9, 0, 0);
        let n = 400_000;
        for p in cases() {
            let xs: Vec<f64> = (0..n).map(|_| p.sample_cos(s.uniform2())).collect();
            let mean = xs.iter().sum::<f64>() / n as f64;
            let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
            let se = (var / n as f64).sqrt();
            assert!(
                (mean - p.mean_cosine()).abs() < 4.0 * se + 1e-12,
                "{p:?}: mean {mean} vs {} (se {se})",
                p.mean_cosine()
            );
        }
    }

    /// Pearson chi-square of sampled cos θ against the CDF, judged by the Wilson–Hilferty
    /// normal approximation at z > 4 (p ≈ 3e-5 per test).
    #[test]
    fn sampled_cosines_follow_the_phase_function() {
        let mut s = Stream::new(11, 0, 0);
        let n = 200_000usize;
        let bins = 64usize;
        for p in cases() {
            let mut counts = vec![0f64; bins];
            for _ in 0..n {
                let mu = p.sample_cos(s.uniform2());
                let b = (((mu + 1.0) * 0.5 * bins as f64) as usize).min(bins - 1);
                counts[b] += 1.0;
            }
            let mut chi2 = 0.0;
            let mut dof = 0usize;
            for (b, c) in counts.iter().enumerate() {
                let lo = -1.0 + 2.0 * b as f64 / bins as f64;
                let hi = lo + 2.0 / bins as f64;
                let expected = n as f64 * (p.cdf_cos(hi) - p.cdf_cos(lo));
                if expected > 5.0 {
                    chi2 += (c - expected).powi(2) / expected;
                    dof += 1;
                }
            }
            let k = (dof - 1) as f64;
            let z = ((chi2 / k).cbrt() - (1.0 - 2.0 / (9.0 * k))) / (2.0 / (9.0 * k)).sqrt();
            assert!(z < 4.0, "{p:?}: chi2 {chi2} dof {k} z {z}");
        }
    }

    #[test]
    fn bad_parameters_are_refused() {
        assert!(PhaseFunction::hg_with_isotropic(1.0, 0.0).is_err());
        assert!(PhaseFunction::hg_with_isotropic(0.5, 1.5).is_err());
        assert!(PhaseFunction::multi_lobe(&[(0.5, 0.9)]).is_err());
        assert!(PhaseFunction::multi_lobe(&[]).is_err());
        assert!(PhaseFunction::HenyeyGreenstein { g: f64::NAN }
            .validate()
            .is_err());
    }

    #[test]
    fn sampled_direction_has_sampled_cosine_about_travel_direction() {
        let p = PhaseFunction::HenyeyGreenstein { g: 0.8 };
        let d = Vec3::new(0.3, 0.4, -0.5).normalize();
        let w = p.sample(d, [0.25, 0.5], (0.6, 0.8));
        assert!((w.dot(d) - p.sample_cos([0.25, 0.5])).abs() < 1e-12);
    }
}
