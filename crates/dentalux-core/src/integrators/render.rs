//! Rendering one band: the dispatch on `settings.integrator`
//! ([`Settings`](super::settings::Settings), docs/render-contract.md).
//!
//! Progress (`control.done()`) counts photons traced plus pixels finished: a progress bar's
//! total is `photons` (0 for `path`) + width × height.

use super::settings::{Integrator, Settings, Stats, VolumeEstimator};
use crate::control::Control;
use crate::error::{Error, Result};
use crate::rng::pass_seed;
use crate::scene::Scene;
use std::time::Instant;

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
            seed: pass_seed(settings.seed, settings.pass_index),
            ..*settings
        };
        &reseeded
    } else {
        settings
    };
    if settings.estimator() == VolumeEstimator::Beam && !scene.media.iter().any(|m| m.sigma_s > 0.0)
    {
        let what = if settings.integrator == Integrator::Bre {
            "settings.integrator = \"bre\""
        } else {
            "settings.volume_estimator = \"beam\""
        };
        return Err(Error::InvalidInput(format!(
            "{what} estimates light scattered in media, and this scene has no scattering \
             medium (every medium has mus = 0): use \"pm\" or \"path\""
        )));
    }
    let (image, mut stats) = match settings.integrator {
        Integrator::Path => super::path::render(scene, settings, control)?,
        Integrator::Pm => super::pm::render(scene, settings, control)?,
        Integrator::Vpm | Integrator::Bre => super::vpm::render(scene, settings, control, false)?,
        Integrator::VpmFull => super::vpm::render(scene, settings, control, true)?,
        Integrator::Volpath => super::volpath::render(scene, settings, control, false)?,
        Integrator::VolpathNee => super::volpath::render(scene, settings, control, true)?,
        Integrator::Ppm => super::ppm::render(scene, settings, control)?,
    };
    stats.seconds_total = t0.elapsed().as_secs_f64();
    stats.spp = settings.spp;
    Ok((image, stats))
}

/// Render several bands of one scene (`scenes[b]`, e.g. from
/// [`band_scenes_from_json`](crate::contract::band_scenes_from_json), which share their
/// shapes and BVH), band `b` with its random-stream key `band_keys[b]` in place of
/// `settings.band`. Each band is the image [`render_band`] gives for that scene and key.
pub fn render_bands(
    scenes: &[Scene],
    settings: &Settings,
    band_keys: &[u64],
    control: &Control,
) -> Result<Vec<(Vec<f32>, Stats)>> {
    if band_keys.len() != scenes.len() {
        return Err(Error::InvalidInput(format!(
            "band_keys has {} entries for {} bands: one key per band",
            band_keys.len(),
            scenes.len()
        )));
    }
    scenes
        .iter()
        .zip(band_keys)
        .map(|(scene, &band)| render_band(scene, &Settings { band, ..*settings }, control))
        .collect()
}
