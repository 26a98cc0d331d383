//! Deterministic random streams: every batch of photons and every tile of pixels derives its
//! own generator from (seed, band, batch), so results do not depend on thread or machine count.
//!
//! The batch index carries a tag saying whose stream it is, so no two users of one seed ever
//! draw from the same stream: camera tiles use small indices (the tile number),
//! [`PHOTON_STREAM`] marks photon batches (plus [`pass_tag`] of a `ppm` pass and
//! [`SURFACE_PASS`] for a surface-only photon pass), [`FILM_STREAM`] the film's sub-pixel
//! rotations. Passes of one render also differ in their seed: [`pass_seed`] puts the pass
//! number into bits [`PASS_SHIFT`] .. [`PASS_SHIFT`] + [`PASS_BITS`] of it.

use rand_core::{RngCore, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// Tag mixed into the batch index of photon streams (camera tiles use small indices).
pub const PHOTON_STREAM: u64 = 1 << 48;

/// Tag of the streams of the surface-only photon pass that completes a camera pass's surface
/// map when a stored budget stopped the volume pass before `photons`
/// (`integrators::photon_trace::trace_camera_maps`).
pub const SURFACE_PASS: u64 = 1 << 44;

/// Stream tag of the film's sub-pixel rotations (apart from tiles' and photons' streams).
pub const FILM_STREAM: u64 = 1 << 60;

/// Bits of a pass number in [`pass_seed`] and [`pass_tag`]: passes are below 2^`PASS_BITS`.
pub const PASS_BITS: u32 = 12;

/// Where [`pass_seed`] puts the pass number: bits `PASS_SHIFT` .. `PASS_SHIFT` +
/// [`PASS_BITS`] of the seed.
pub const PASS_SHIFT: u32 = 40;

/// Seed of the camera pass of pass `pass` (1-based): `seed ^ (pass << 40)`. `ppm` uses it per
/// pass; the other integrators for their `pass_index` > 0, so every pass has its own streams.
pub fn pass_seed(seed: u64, pass: u32) -> u64 {
    seed ^ ((pass as u64) << PASS_SHIFT)
}

/// `seed` without the bits [`pass_seed`] flips: the same for every pass of one seed.
pub fn seed_without_pass(seed: u64) -> u64 {
    seed & !(((1u64 << PASS_BITS) - 1) << PASS_SHIFT)
}

/// Tag of the photon streams of `ppm` pass `pass` (1-based): `pass · 2³²` (below
/// [`SURFACE_PASS`], since passes are below 2^[`PASS_BITS`]).
pub fn pass_tag(pass: u32) -> u64 {
    (pass as u64) << 32
}

/// Stream key offset of a specimen reading's flipped run (diffuse light from below, the
/// adding formula's R2 and T2): band k's run is keyed `DIFFUSE_RUN_KEY + k`.
pub const DIFFUSE_RUN_KEY: u64 = 100_000;
/// Stream key offset of a specimen reading's separate transmitted run (the disc in air when
/// the reading itself has an optical contact): `TRANSMITTED_RUN_KEY + k`.
pub const TRANSMITTED_RUN_KEY: u64 = 200_000;
/// Stream key offset of the run that corrects a laterally infinite reading for the
/// specimen's rim ([`crate::integrators::slab::BackingOrders::past_rim_only`]): `RIM_RUN_KEY
/// + k`, and `RIM_RUN_KEY + TRANSMITTED_RUN_KEY + k` for its transmitted run.
pub const RIM_RUN_KEY: u64 = 300_000;

/// A random stream (xoshiro256++), keyed by (seed, band, batch).
#[derive(Debug, Clone)]
pub struct Stream(Xoshiro256PlusPlus);

/// SplitMix64 finaliser: decorrelates nearby keys before seeding.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl Stream {
    /// The stream for (seed, band, batch).
    pub fn new(seed: u64, band: u64, batch: u64) -> Self {
        let key = mix(mix(mix(seed) ^ band.wrapping_mul(0xA24B_AED4_963E_E407)) ^ batch);
        Self(Xoshiro256PlusPlus::seed_from_u64(key))
    }
    /// Uniform in [0, 1) with 53 random bits.
    #[inline]
    pub fn uniform(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
    /// 64 raw random bits (e.g. two 32-bit uniforms where 32 bits of resolution suffice).
    #[inline]
    pub fn next_bits(&mut self) -> u64 {
        self.0.next_u64()
    }
    /// Uniform in (0, 1]: safe as the argument of a logarithm.
    #[inline]
    pub fn uniform_open0(&mut self) -> f64 {
        1.0 - self.uniform()
    }
    /// Two uniforms in [0, 1).
    #[inline]
    pub fn uniform2(&mut self) -> [f64; 2] {
        [self.uniform(), self.uniform()]
    }
    /// (cos φ, sin φ) of an azimuth φ uniform on [0, 2π), without trigonometry: a point
    /// (x, y) uniform in the unit disc (by rejection from the square, two 32-bit coordinates
    /// per draw, 4/π draws on average) has a uniform polar angle θ, and its double angle is
    /// (x² − y², 2xy) / (x² + y²). glibc's sin_cos was 4 % of a photon pass (Fig. 3's discs).
    #[inline]
    pub fn azimuth(&mut self) -> (f64, f64) {
        const SCALE: f64 = 1.0 / (1u64 << 31) as f64;
        loop {
            let bits = self.0.next_u64();
            let x = (bits as u32) as f64 * SCALE - 1.0;
            let y = (bits >> 32) as f64 * SCALE - 1.0;
            let r2 = x * x + y * y;
            if r2 <= 1.0 && r2 > 0.0 {
                return ((x * x - y * y) / r2, 2.0 * x * y / r2);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_reproducible_and_distinct() {
        let a: Vec<f64> = (0..4).map(|_| Stream::new(1, 0, 7).uniform()).collect();
        let mut s = Stream::new(1, 0, 7);
        let b = s.uniform();
        assert_eq!(a[0], b);
        let mut t = Stream::new(1, 0, 8);
        let mut u = Stream::new(1, 1, 7);
        assert_ne!(t.uniform(), b);
        assert_ne!(u.uniform(), b);
    }

    #[test]
    fn uniform_mean_and_bounds() {
        let mut s = Stream::new(42, 0, 0);
        let n = 200_000;
        let mut sum = 0.0;
        for _ in 0..n {
            let x = s.uniform();
            assert!((0.0..1.0).contains(&x));
            let y = s.uniform_open0();
            assert!(y > 0.0 && y <= 1.0);
            sum += x;
        }
        let mean = sum / n as f64;
        // stderr of the mean of U(0,1) is sqrt(1/12/n); allow 4 of them
        assert!((mean - 0.5).abs() < 4.0 * (1.0 / 12.0 / n as f64).sqrt());
    }

    /// The azimuth is a unit vector whose angle is uniform: 32 equal sectors of the circle
    /// by a chi-square test (31 degrees of freedom; 60 is exceeded with probability 1e-3),
    /// and cos 2φ, sin 2φ (which the rejection's double angle would skew first) average 0
    /// within 4 standard errors (each has variance 1/2).
    #[test]
    fn azimuth_is_a_uniform_unit_vector() {
        let mut s = Stream::new(3, 0, 1);
        let (n, bins) = (320_000usize, 32usize);
        let mut count = vec![0usize; bins];
        let (mut c2, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let (c, sn) = s.azimuth();
            assert!((c * c + sn * sn - 1.0).abs() < 1e-14);
            let phi = sn.atan2(c).rem_euclid(std::f64::consts::TAU);
            count[((phi / std::f64::consts::TAU * bins as f64) as usize).min(bins - 1)] += 1;
            c2 += c * c - sn * sn;
            s2 += 2.0 * c * sn;
        }
        let e = n as f64 / bins as f64;
        let chi2: f64 = count.iter().map(|&k| (k as f64 - e).powi(2) / e).sum();
        assert!(chi2 < 60.0, "chi-square {chi2} over {bins} sectors");
        let tol = 4.0 * (0.5 / n as f64).sqrt();
        assert!((c2 / n as f64).abs() < tol && (s2 / n as f64).abs() < tol);
    }
}
