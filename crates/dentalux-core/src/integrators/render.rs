//! Rendering one band: the settings of the render contract (docs/render-contract.md), the
//! statistics returned with the image, the tile loop every camera pass shares, and the
//! dispatch on `settings.integrator`.
//!
//! Tiles are [`TILE`]² pixels in row-major tile order; tile i draws from
//! `Stream::new(seed, band, i)` (photon batches use indices tagged with
//! [`crate::integrators::photon_trace::PHOTON_STREAM`], so the streams never meet). Tiles run
//! in parallel (rayon) and are written in index order, so an image does not depend on the
//! number of threads. The control is checked before each tile row and every 256 samples of a
//! pixel, so a cancel stops a render within one tile row (or 256 samples) per thread.
//!
//! Progress (`control.done()`) counts photons traced plus pixels finished: a progress bar's
//! total is `photons` (0 for `path`) + width × height.

use crate::control::Control;
use crate::error::{Error, Result};
use crate::film::{Film, Tile, TILE};
use crate::geometry::Ray;
use crate::photon_map::Neighbours;
use crate::rng::Stream;
use crate::sampling::r2_point;
use crate::scene::Scene;
use rayon::prelude::*;
use std::time::Instant;

/// Which integrator renders the band.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Integrator {
    /// Direct light + specular dielectrics + surface photon map (opaque scenes, clear media).
    Pm,
    /// Brute-force path tracer with next-event estimation: the reference for `pm`.
    Path,
    /// Volume photon mapping, single scattering by shadow rays (the paper).
    Vpm,
    /// Volume photon mapping, every scattering event in the map.
    VpmFull,
    /// Reference volumetric path tracer.
    Volpath,
    /// The same, with next-event estimation also through flat refracting faces (planar_nee.rs):
    /// same expectation, a faster reference where light enters media through flat faces.
    VolpathNee,
    /// Progressive photon mapping.
    Ppm,
}

impl Integrator {
    /// Parse the contract's name (`"pm"`, `"path"`, `"vpm"`, `"vpm-full"`, `"volpath"`,
    /// `"volpath-nee"`, `"ppm"`).
    pub fn parse(name: &str) -> Result<Self> {
        Ok(match name {
            "pm" => Integrator::Pm,
            "path" => Integrator::Path,
            "vpm" => Integrator::Vpm,
            "vpm-full" => Integrator::VpmFull,
            "volpath" => Integrator::Volpath,
            "volpath-nee" => Integrator::VolpathNee,
            "ppm" => Integrator::Ppm,
            other => {
                return Err(Error::InvalidInput(format!(
                    "settings.integrator = {other:?}: allowed \"pm\", \"path\", \"vpm\", \"vpm-full\", \"volpath\", \"volpath-nee\", \"ppm\""
                )))
            }
        })
    }
}

/// Default of [`Settings::aim`]: emit as the lights do. Aiming is opt-in because it changes
/// how many photons a given `volume_photons` stores (and so memory and time): on the 5 mm
/// Fig. 3 disc at aim 0.5, 21× more (2.7 M → 56 M from 5 M photons).
pub const DEFAULT_AIM: f64 = 0.0;

/// Render settings (see docs/render-contract.md; `None` = derive from the scene).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// The integrator.
    pub integrator: Integrator,
    /// Camera samples per pixel (≥ 1).
    pub spp: u32,
    /// Photons emitted for the surface photon map.
    pub photons: u64,
    /// Photons emitted for the volume photon maps (with `volume_stored`: at most this many).
    pub volume_photons: u64,
    /// Photons the volume maps of a pass should hold (0: no budget). Photons are emitted until
    /// the maps hold at least this many (the paper counts its
    /// 100 000 000 photons this way) or `volume_photons` have been emitted; powers are
    /// normalised by the number actually emitted.
    pub volume_stored: u64,
    /// Fraction of the volume pass's photons aimed at the scattering media's bounding
    /// spheres, in [0, 1) (`integrators::aim`; unbiased mixture). 0: emit as the lights do.
    pub aim: f64,
    /// Photons per density estimate.
    pub k: usize,
    /// Largest gathering radius [mm].
    pub radius: Option<f64>,
    /// Ray-marching step [mm].
    pub step: Option<f64>,
    /// Seed of every random stream.
    pub seed: u64,
    /// Band index (mixed into the streams only).
    pub band: u64,
    /// Longest path (bounces / boundary events).
    pub max_depth: u32,
    /// Progressive photon mapping passes.
    pub passes: u32,
    /// Progressive photon mapping radius reduction α in (0, 1).
    pub alpha: f64,
    /// First pass to render, 0-based: `ppm` renders passes `pass_index + 1 ..= pass_index +
    /// passes` of its schedule (one task per pass for distributed renders); other
    /// integrators draw from an independent seed stream per pass index (0 = the plain seed).
    pub pass_index: u32,
    /// `pm`: final gathering (one diffuse bounce before the density estimate).
    pub final_gather: bool,
    /// `vpm`, `vpm-full`, `ppm`: half-height of the boundary-aligned layer kernel over the
    /// gathering radius, in [0, 1]; 0 the sphere (see `VpmParams::layer`).
    pub kernel_layer: f64,
    /// `vpm`, `vpm-full`, `ppm`: clip the layer kernel (and vpm's surface disc) by every
    /// other face within it, not only the camera ray's entry and exit planes (see
    /// `VpmParams::clip`).
    pub kernel_clip: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            integrator: Integrator::Pm,
            spp: 16,
            photons: 200_000,
            volume_photons: 1_000_000,
            volume_stored: 0,
            aim: DEFAULT_AIM,
            k: 64,
            radius: None,
            step: None,
            seed: 1,
            band: 0,
            max_depth: 64,
            passes: 1,
            alpha: 0.7,
            pass_index: 0,
            final_gather: false,
            kernel_layer: crate::integrators::vpm::DEFAULT_LAYER,
            kernel_clip: crate::integrators::vpm::DEFAULT_CLIP,
        }
    }
}

impl Settings {
    /// Check ranges; errors name `settings.<key>`.
    pub fn validate(&self) -> Result<()> {
        let bad = |k: &str, msg: &str| Err(Error::InvalidInput(format!("settings.{k} {msg}")));
        if self.spp == 0 {
            return bad("spp", "= 0 is out of range: allowed ≥ 1");
        }
        if self.k == 0 {
            return bad("k", "= 0 is out of range: allowed ≥ 1");
        }
        if self.max_depth == 0 {
            return bad("max_depth", "= 0 is out of range: allowed ≥ 1");
        }
        if self.passes == 0 {
            return bad("passes", "= 0 is out of range: allowed ≥ 1");
        }
        // pass numbers live in 12 bits of the seeds (ppm::pass_seed, film_key)
        let last = self.pass_index as u64 + self.passes as u64;
        if last >= super::ppm::MAX_PASSES as u64 {
            return Err(Error::InvalidInput(format!(
                "settings.pass_index + settings.passes = {last} is out of range: allowed [1, {}]",
                super::ppm::MAX_PASSES - 1
            )));
        }
        for (k, v) in [("radius", self.radius), ("step", self.step)] {
            if let Some(v) = v {
                crate::error::check_positive(&format!("settings.{k}"), v, "mm")?;
            }
        }
        crate::error::check_range("settings.alpha", self.alpha, 0.0, true, 1.0, true, "")?;
        crate::error::check_range("settings.aim", self.aim, 0.0, false, 1.0, true, "")?;
        crate::error::check_range(
            "settings.kernel_layer",
            self.kernel_layer,
            0.0,
            false,
            1.0,
            false,
            "",
        )
    }
}

/// What a render measured besides the image.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Stats {
    /// Integrator name as in the contract.
    pub integrator: String,
    /// Wall-clock seconds of the whole band.
    pub seconds_total: f64,
    /// Seconds tracing photons.
    pub seconds_photons: f64,
    /// Seconds building photon-map kd-trees.
    pub seconds_build: f64,
    /// Seconds of the camera pass.
    pub seconds_camera: f64,
    /// Photons emitted.
    pub photons_emitted: u64,
    /// Photons stored (all maps).
    pub photons_stored: u64,
    /// Bytes per stored photon.
    pub bytes_per_photon: u64,
    /// Memory of all photon maps [bytes].
    pub photon_map_bytes: u64,
    /// Surface gathering radius in use [mm] (0 when none).
    pub radius: f64,
    /// Rays traced by the camera pass (intersection and shadow queries).
    pub rays: u64,
    /// Camera samples per pixel.
    pub spp: u32,
    /// Integrator-specific figures (name, value).
    pub extra: Vec<(String, f64)>,
}

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

/// Stream tag of the film's sub-pixel rotations (apart from tiles' and photons' streams).
const FILM_STREAM: u64 = 1 << 60;

/// The key of a pixel's sub-pixel sequence: the seed without the bits [`ppm::pass_seed`]
/// flips per pass, and the first sample of this pass, `pass_index` · spp. Every pass of a
/// seed walks on along one randomly rotated R2 sequence per pixel, so N averaged passes
/// stratify the pixel like one render with N · spp samples: on Fig. 3 the pixel footprint
/// (checker edges, rims) is most of the camera pass's noise, and independent rotations per
/// pass left it falling only as 1/N (docs/vpm-convergence.md, fifth session). Each sample is
/// still uniform over its pixel, so every pass stays unbiased on its own.
///
/// [`ppm::pass_seed`]: super::ppm::pass_seed
fn film_key(settings: &Settings) -> (u64, u64) {
    let seed = settings.seed & !(((super::ppm::MAX_PASSES as u64) - 1) << super::ppm::PASS_SHIFT);
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
    let cam = &scene.camera;
    let mut film = Film::new(cam.width, cam.height);
    let tiles = film.tiles();
    let spp = settings.spp;
    let (film_seed, first) = film_key(settings);
    let done: Vec<(Vec<f32>, Totals)> = tiles
        .par_iter()
        .map(|tile: &Tile| {
            control.check()?;
            let mut rng = Stream::new(settings.seed, settings.band, tile.index);
            let mut subpixel = Stream::new(film_seed, settings.band, FILM_STREAM | tile.index);
            let mut scratch = Scratch::default();
            let mut px = Vec::with_capacity(TILE * TILE);
            for y in tile.y0..tile.y1 {
                // a row of a tile is the longest stretch between checks: high spp stays prompt
                control.check()?;
                for x in tile.x0..tile.x1 {
                    let mut sum = 0.0;
                    // stratified sub-pixel positions: R2 points with a random rotation
                    let shift = subpixel.uniform2();
                    for i in 0..spp {
                        // very high spp: check within a pixel too (an atomic load)
                        if i % 256 == 255 {
                            control.check()?;
                        }
                        let [jx, jy] = r2_point(first + i as u64, shift);
                        let ray = cam.ray(x as f64 + jx, y as f64 + jy);
                        sum += radiance(&ray, &mut rng, &mut scratch);
                    }
                    px.push((sum / spp as f64) as f32);
                }
            }
            control.add_done(px.len() as u64);
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
        film.put(tile, &px);
        totals.rays += t.rays;
        totals.radius_sum += t.radius_sum;
        totals.estimates += t.estimates;
    }
    Ok((film.data, totals))
}

/// Render one band of `scene` with `settings`: the H × W radiance image (row-major, row 0
/// at the top) and the statistics.
pub fn render_band(
    scene: &Scene,
    settings: &Settings,
    control: &Control,
) -> Result<(Vec<f32>, Stats)> {
    settings.validate()?;
    let t0 = Instant::now();
    let reseeded;
    let settings = if settings.pass_index > 0 && settings.integrator != Integrator::Ppm {
        reseeded = Settings {
            seed: super::ppm::pass_seed(settings.seed, settings.pass_index),
            ..*settings
        };
        &reseeded
    } else {
        settings
    };
    let (image, mut stats) = match settings.integrator {
        Integrator::Path => super::path::render(scene, settings, control)?,
        Integrator::Pm => super::pm::render(scene, settings, control)?,
        Integrator::Vpm => super::vpm::render(scene, settings, control, false)?,
        Integrator::VpmFull => super::vpm::render(scene, settings, control, true)?,
        Integrator::Volpath => super::volpath::render(scene, settings, control, false)?,
        Integrator::VolpathNee => super::volpath::render(scene, settings, control, true)?,
        Integrator::Ppm => super::ppm::render(scene, settings, control)?,
    };
    stats.seconds_total = t0.elapsed().as_secs_f64();
    stats.spp = settings.spp;
    Ok((image, stats))
}
