//! Warps from uniform numbers to the distributions photon transport needs, with their pdfs.

use crate::math::Vec3;
use std::f64::consts::PI;

/// Free-flight distance of eq. 2, d = −ln ξ / σt, for ξ in (0, 1].
/// Returns +∞ when σt = 0 (the photon never interacts).
#[inline]
pub fn sample_exponential(u_open0: f64, sigma_t: f64) -> f64 {
    if sigma_t > 0.0 {
        -u_open0.ln() / sigma_t
    } else {
        f64::INFINITY
    }
}

/// Uniform direction on the unit sphere; pdf 1/(4π).
pub fn uniform_sphere(u: [f64; 2]) -> Vec3 {
    let z = 1.0 - 2.0 * u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = (2.0 * PI * u[1]).sin_cos();
    Vec3::new(r * c, r * s, z)
}

/// Cosine-weighted direction about +z; pdf cos θ / π.
pub fn cosine_hemisphere(u: [f64; 2]) -> Vec3 {
    let r = u[0].sqrt();
    let (s, c) = (2.0 * PI * u[1]).sin_cos();
    Vec3::new(r * c, r * s, (1.0 - u[0]).max(0.0).sqrt())
}

/// Uniform point on the unit disc (concentric-free polar map; fine for area lights).
pub fn uniform_disc(u: [f64; 2]) -> (f64, f64) {
    let r = u[0].sqrt();
    let (s, c) = (2.0 * PI * u[1]).sin_cos();
    (r * c, r * s)
}

/// Uniform azimuth φ in [0, 2π), returned as (cos φ, sin φ) without trigonometric calls;
/// see [`sample_azimuth_scaled`]. `next` yields uniforms in [0, 1).
#[inline]
pub fn sample_azimuth(next: impl FnMut() -> f64) -> (f64, f64) {
    let (c, s, rho) = sample_azimuth_scaled(next);
    (c / rho, s / rho)
}

/// Uniform azimuth as (ρ cos φ, ρ sin φ, ρ) with ρ in (0, 1]: a point (x, y) uniform in the
/// unit disc (by rejection from the square, acceptance π/4) has a uniform polar angle α, and
/// (x² − y², 2xy) = r² (cos 2α, sin 2α). Leaving out the division by ρ = r² lets the caller
/// fold it into its own (see [`crate::math::rotate_direction_scaled`]). `next` yields
/// uniforms in [0, 1); it is called an even number of times (2.55 on average).
#[inline]
pub fn sample_azimuth_scaled(mut next: impl FnMut() -> f64) -> (f64, f64, f64) {
    loop {
        let x = 2.0 * next() - 1.0;
        let y = 2.0 * next() - 1.0;
        let r2 = x * x + y * y;
        // r2 = 0 has no angle; r2 > 1 lies outside the disc
        if r2 <= 1.0 && r2 > 0.0 {
            return (x * x - y * y, 2.0 * x * y, r2);
        }
    }
}

/// [`sample_azimuth_scaled`] from 64 random bits per try (x and y from 32 bits each, ample
/// resolution for an angle): about half the generator calls of the two-uniform version.
#[inline]
pub fn sample_azimuth_scaled_bits(mut next_bits: impl FnMut() -> u64) -> (f64, f64, f64) {
    const SCALE: f64 = 1.0 / (1u64 << 31) as f64;
    loop {
        let b = next_bits();
        // (b >> 32) and the low word are uniform integers in [0, 2^32): map to [-1, 1)
        let x = (b >> 32) as f64 * SCALE - 1.0;
        let y = (b & 0xFFFF_FFFF) as f64 * SCALE - 1.0;
        let r2 = x * x + y * y;
        // r2 = 0 has no angle; r2 > 1 lies outside the disc
        if r2 <= 1.0 && r2 > 0.0 {
            return (x * x - y * y, 2.0 * x * y, r2);
        }
    }
}

/// Index drawn from unnormalised non-negative `weights` by inverting their CDF.
pub fn sample_discrete(weights: &[f64], u: f64) -> usize {
    let total: f64 = weights.iter().sum();
    let mut target = u * total;
    for (i, w) in weights.iter().enumerate() {
        if target < *w {
            return i;
        }
        target -= w;
    }
    weights.len() - 1
}

/// Point `i` of the R2 low-discrepancy sequence in [0, 1)², rotated by `shift`
/// (Cranley–Patterson): with a uniform random shift every point is uniform on its own (so an
/// average over points stays unbiased) while the points together cover the square far more
/// evenly than independent ones. Used for the sub-pixel positions of camera samples; any run
/// of consecutive points is as even, so averaged passes can continue one sequence.
#[inline]
pub fn r2_point(i: u64, shift: [f64; 2]) -> [f64; 2] {
    // 1/φ₂ and 1/φ₂², φ₂ the plastic number (root of x³ = x + 1)
    const A1: f64 = 0.754_877_666_246_692_7;
    const A2: f64 = 0.569_840_290_998_053_2;
    let i = i as f64;
    [(shift[0] + i * A1).fract(), (shift[1] + i * A2).fract()]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Stream;

    #[test]
    fn exponential_mean_is_mean_free_path() {
        let mut s = Stream::new(3, 0, 0);
        let n = 200_000;
        let sigma_t = 2.5;
        let mean: f64 = (0..n)
            .map(|_| sample_exponential(s.uniform_open0(), sigma_t))
            .sum::<f64>()
            / n as f64;
        // variance of Exp(σt) is 1/σt²
        assert!((mean - 1.0 / sigma_t).abs() < 4.0 / sigma_t / (n as f64).sqrt());
        assert!(sample_exponential(0.5, 0.0).is_infinite());
    }

    #[test]
    fn cosine_hemisphere_mean_cosine_is_two_thirds() {
        let mut s = Stream::new(4, 0, 0);
        let n = 200_000;
        let mean: f64 = (0..n)
            .map(|_| cosine_hemisphere(s.uniform2()).z)
            .sum::<f64>()
            / n as f64;
        // E[cos] = 2/3, Var = 1/2 - 4/9 = 1/18
        assert!((mean - 2.0 / 3.0).abs() < 4.0 * (1.0 / 18.0 / n as f64).sqrt());
    }

    /// The azimuth is uniform: its cos and sin have mean 0 and variance 1/2, the point is on
    /// the unit circle, and the fraction with φ in the first quadrant is 1/4.
    #[test]
    fn azimuth_is_uniform_on_the_circle() {
        let mut s = Stream::new(5, 0, 0);
        let n = 200_000;
        let (mut sc, mut ss, mut scc, mut q1) = (0.0, 0.0, 0.0, 0.0);
        for i in 0..n {
            let (c, si) = if i % 2 == 0 {
                sample_azimuth(|| s.uniform())
            } else {
                let (c, si, rho) = sample_azimuth_scaled_bits(|| s.next_bits());
                (c / rho, si / rho)
            };
            assert!((c * c + si * si - 1.0).abs() < 1e-12);
            sc += c;
            ss += si;
            scc += c * c;
            if c > 0.0 && si > 0.0 {
                q1 += 1.0;
            }
        }
        let nf = n as f64;
        let se = (0.5 / nf).sqrt();
        assert!((sc / nf).abs() < 4.0 * se && (ss / nf).abs() < 4.0 * se);
        // Var(cos²φ) = 3/8 - 1/4 = 1/8
        assert!((scc / nf - 0.5).abs() < 4.0 * (0.125 / nf).sqrt());
        assert!((q1 / nf - 0.25).abs() < 4.0 * (0.1875 / nf).sqrt());
    }

    /// 64 rotated R2 points put 4 ± 2 points in each cell of a 4×4 grid for any rotation
    /// (independent points: up to ±11 seen in 2000 trials).
    #[test]
    fn r2_points_are_uniform_and_even() {
        let mut s = Stream::new(5, 0, 0);
        for _ in 0..200 {
            let shift = s.uniform2();
            let mut cells = [0i32; 16];
            for i in 0..64 {
                let [x, y] = r2_point(i as u64, shift);
                assert!((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y));
                cells[(x * 4.0) as usize * 4 + (y * 4.0) as usize] += 1;
            }
            assert!(cells.iter().all(|c| (c - 4).abs() <= 2), "{cells:?}");
        }
    }

    #[test]
    fn discrete_picks_by_weight() {
        assert_eq!(sample_discrete(&[1.0, 0.0, 3.0], 0.1), 0);
        assert_eq!(sample_discrete(&[1.0, 0.0, 3.0], 0.3), 2);
        assert_eq!(sample_discrete(&[1.0, 0.0, 3.0], 0.9999), 2);
    }
}
