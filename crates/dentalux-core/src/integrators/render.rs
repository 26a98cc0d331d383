//! Rendering one band, or all bands of a scene: the dispatch on `settings.integrator`
//! ([`Settings`](super::settings::Settings), docs/render-contract.md).
//!
//! Progress (`control.done()`) counts photons traced plus pixels finished: a progress bar's
//! total is `photons` (0 for `path`) + width × height.

use super::photon_trace::{trace_camera_maps, trace_camera_maps_bands};
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
    let t0 = Instant::now();
    let settings = &effective(scene, settings)?;
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

/// The settings a band renders with, checked: validated, the seed of pass `pass_index` for
/// the one-pass integrators (`ppm` schedules its passes itself), and the beam refused in a
/// scene without a scattering medium.
fn effective(scene: &Scene, settings: &Settings) -> Result<Settings> {
    settings.validate()?;
    let mut s = *settings;
    if s.pass_index > 0 && s.integrator != Integrator::Ppm {
        s.seed = pass_seed(s.seed, s.pass_index);
    }
    if s.estimator() == VolumeEstimator::Beam && !scene.media.iter().any(|m| m.sigma_s > 0.0) {
        let what = if s.integrator == Integrator::Bre {
            "settings.integrator = \"bre\""
        } else {
            "settings.volume_estimator = \"beam\""
        };
        return Err(Error::InvalidInput(format!(
            "{what} estimates light scattered in media, and this scene has no scattering \
             medium (every medium has mus = 0): use \"pm\" or \"path\""
        )));
    }
    Ok(s)
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
    if (settings.spectral_photons || settings.hero_camera) && scenes.len() > 1 {
        return render_together(scenes, settings, band_keys, control);
    }
    scenes
        .iter()
        .zip(band_keys)
        .map(|(scene, &band)| render_band(scene, &Settings { band, ..*settings }, control))
        .collect()
}

/// [`render_bands`] with the bands' photon maps, or their camera paths, shared: one spectral
/// photon pass for all bands (`settings.spectral_photons`, `integrators::hero`) or one
/// photon pass per band with its own key; then one camera pass per band over its maps, or
/// one for all bands (`settings.hero_camera`, `integrators::hero_camera`). The camera
/// passes draw the streams of the first band's key, so a pixel sample follows the same
/// path in every band where the indices agree. A spectral pass traces its photons once:
/// progress counts them once.
fn render_together(
    scenes: &[Scene],
    settings: &Settings,
    band_keys: &[u64],
    control: &Control,
) -> Result<Vec<(Vec<f32>, Stats)>> {
    let t0 = Instant::now();
    let band = |b: usize| {
        effective(
            &scenes[b],
            &Settings {
                band: band_keys[b],
                ..*settings
            },
        )
    };
    let first = band(0)?;
    let full = first.integrator == Integrator::VpmFull;
    let mode = super::vpm::store_mode(full);
    let all = if first.spectral_photons {
        for (b, scene) in scenes.iter().enumerate().skip(1) {
            effective(scene, &first)?;
            // a walk starts on the hero's light: every band must have it where the hero has it
            for (i, (l, l0)) in scene.lights.iter().zip(&scenes[0].lights).enumerate() {
                if !l.same_place(l0) {
                    return Err(Error::InvalidInput(format!(
                        "bands[{b}].lights[{i}] is not the light bands[0].lights[{i}] is, only \
                         brighter or dimmer: a spectral photon pass (settings.spectral_photons) \
                         needs every band's lights in the same places"
                    )));
                }
            }
        }
        trace_camera_maps_bands(scenes, &first, mode, 0, control)?
    } else {
        (scenes.iter().enumerate())
            .map(|(b, scene)| trace_camera_maps(scene, &band(b)?, mode, 0, control))
            .collect::<Result<Vec<_>>>()?
    };
    // a spectral pass's tracing time, shared by its bands
    let traced = t0.elapsed().as_secs_f64() / scenes.len() as f64;
    let mut out = Vec::with_capacity(scenes.len());
    if first.hero_camera {
        let t = Instant::now();
        let bands = super::hero_camera::render_with_maps(scenes, &first, control, full, &all)?;
        let each = t.elapsed().as_secs_f64() / scenes.len() as f64;
        out.extend(bands.into_iter().map(|band| (band, each)));
    } else {
        // every band's camera pass draws the same random numbers (the first band's key):
        // with the same photons and the same camera paths the bands' noise is shared
        for (scene, maps) in scenes.iter().zip(&all) {
            let t = Instant::now();
            let band = super::vpm::render_with_maps(scene, &first, control, full, maps)?;
            out.push((band, t.elapsed().as_secs_f64()));
        }
    }
    let out = out
        .into_iter()
        .map(|((image, mut stats), camera)| {
            stats.seconds_total = traced + camera;
            stats.spp = first.spp;
            if first.spectral_photons {
                stats.extra.push(("spectral_photons".into(), 1.0));
            }
            (image, stats)
        })
        .collect();
    Ok(out)
}
