//! The tile loop every camera pass shares, with its per-thread scratch.
//!
//! Tiles are [`TILE`]² pixels in row-major tile order; tile i draws from
//! `Stream::new(seed, band, i)` (photon batches use indices tagged with
//! [`crate::rng::PHOTON_STREAM`], so the streams never meet). Tiles run in parallel (rayon)
//! and are written in index order, so an image does not depend on the number of threads. The
//! control is checked before each tile row and every 256 samples of a pixel, so a cancel
//! stops a render within one tile row (or 256 samples) per thread.

use super::settings::Settings;
use crate::control::Control;
use crate::error::Result;
use crate::film::{Film, Tile, TILE};
use crate::geometry::Ray;
use crate::photon_map::Neighbours;
use crate::rng::{seed_without_pass, Stream, FILM_STREAM};
use crate::sampling::r2_point;
use crate::scene::Scene;
use rayon::prelude::*;

/// Per-thread scratch of a camera pass.
#[derive(Debug, Default)]
pub struct Scratch {
    /// k-NN buffer.
    pub nb: Neighbours,
    /// Rays traced.
    pub rays: u64,
    /// Sum of the gathering radii of the density estimates made [mm].
    pub radius_sum: f64,
    /// Density estimates made.
    pub estimates: u64,
}

/// Counters of a camera pass, summed over tiles in tile order.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Totals {
    /// Rays traced.
    pub rays: u64,
    /// Sum of gathering radii [mm].
    pub radius_sum: f64,
    /// Density estimates made.
    pub estimates: u64,
}

impl Totals {
    /// Mean gathering radius [mm] (0 when no estimate was made).
    pub fn mean_radius(&self) -> f64 {
        if self.estimates > 0 {
            self.radius_sum / self.estimates as f64
        } else {
            0.0
        }
    }
}

/// The key of a pixel's sub-pixel sequence: the seed without the bits [`pass_seed`]
/// flips per pass, and the first sample of this pass, `pass_index` · spp. Every pass of a
/// seed walks on along one randomly rotated R2 sequence per pixel, so N averaged passes
/// stratify the pixel like one render with N · spp samples: on Fig. 3 the pixel footprint
/// (checker edges, rims) is most of the camera pass's noise, and independent rotations per
/// pass left it falling only as 1/N (docs/notes/2026-12-02-vpm-convergence.md). Each sample is
/// still uniform over its pixel, so every pass stays unbiased on its own.
///
/// [`pass_seed`]: crate::rng::pass_seed
fn film_key(settings: &Settings) -> (u64, u64) {
    let seed = seed_without_pass(settings.seed);
    (seed, settings.pass_index as u64 * settings.spp as u64)
}

/// Render the film tile by tile: `radiance(ray, rng, scratch)` is called `spp` times per
/// pixel with camera rays through randomly rotated R2 sub-pixel positions (stratified,
/// each unbiased; passes of one seed continue the sequence, [`film_key`]) and averaged.
/// Returns the image and the summed counters.
pub fn render_tiles<F>(
    scene: &Scene,
    settings: &Settings,
    control: &Control,
    radiance: F,
) -> Result<(Vec<f32>, Totals)>
where
    F: Fn(&Ray, &mut Stream, &mut Scratch) -> f64 + Sync,
{
    let (mut images, totals) =
        render_tiles_bands(scene, settings, control, 1, |ray, rng, sc, sum| {
            sum[0] += radiance(ray, rng, sc);
        })?;
    Ok((images.swap_remove(0), totals))
}

/// [`render_tiles`] for a camera pass that measures `bands` bands at once: `radiance(ray,
/// rng, scratch, sum)` adds each band's radiance along the camera ray to `sum[b]`. Returns
/// one image per band. Progress counts a pixel once per band, as `bands` one-band passes
/// would.
pub fn render_tiles_bands<F>(
    scene: &Scene,
    settings: &Settings,
    control: &Control,
    bands: usize,
    radiance: F,
) -> Result<(Vec<Vec<f32>>, Totals)>
where
    F: Fn(&Ray, &mut Stream, &mut Scratch, &mut [f64]) + Sync,
{
    let cam = &scene.camera;
    let mut films: Vec<Film> = (0..bands)
        .map(|_| Film::new(cam.width, cam.height))
        .collect();
    let tiles = films[0].tiles();
    let spp = settings.spp;
    let (film_seed, first) = film_key(settings);
    let done: Vec<(Vec<Vec<f32>>, Totals)> = tiles
        .par_iter()
        .map(|tile: &Tile| {
            control.check()?;
            let mut rng = Stream::new(settings.seed, settings.band, tile.index);
            let mut subpixel = Stream::new(film_seed, settings.band, FILM_STREAM | tile.index);
            let mut scratch = Scratch::default();
            let mut px = vec![Vec::with_capacity(TILE * TILE); bands];
            let mut sum = vec![0.0; bands];
            for y in tile.y0..tile.y1 {
                // a row of a tile is the longest stretch between checks: high spp stays prompt
                control.check()?;
                for x in tile.x0..tile.x1 {
                    sum.fill(0.0);
                    // stratified sub-pixel positions: R2 points with a random rotation
                    let shift = subpixel.uniform2();
                    for i in 0..spp {
                        // very high spp: check within a pixel too (an atomic load)
                        if i % 256 == 255 {
                            control.check()?;
                        }
                        let [jx, jy] = r2_point(first + i as u64, shift);
                        let ray = cam.ray(x as f64 + jx, y as f64 + jy);
                        radiance(&ray, &mut rng, &mut scratch, &mut sum);
                    }
                    for (p, s) in px.iter_mut().zip(&sum) {
                        p.push((s / spp as f64) as f32);
                    }
                }
            }
            control.add_done((px[0].len() * bands) as u64);
            let totals = Totals {
                rays: scratch.rays,
                radius_sum: scratch.radius_sum,
                estimates: scratch.estimates,
            };
            Ok((px, totals))
        })
        .collect::<Result<Vec<_>>>()?;
    let mut totals = Totals::default();
    for (tile, (px, t)) in tiles.iter().zip(done) {
        for (film, px) in films.iter_mut().zip(&px) {
            film.put(tile, px);
        }
        totals.rays += t.rays;
        totals.radius_sum += t.radius_sum;
        totals.estimates += t.estimates;
    }
    Ok((films.into_iter().map(|f| f.data).collect(), totals))
}
