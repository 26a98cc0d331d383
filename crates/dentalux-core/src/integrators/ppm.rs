//! Probabilistic progressive photon mapping (in the style of Knaus & Zwicker 2011) for
//! scenes with media: independent passes, each with its own photon maps of a fixed size
//! (memory is bounded by one pass), each rendered with fixed gathering radii that shrink by a
//! known schedule; the pass images are averaged. Bias and noise both vanish as passes grow, so
//! the average converges to the `volpath` answer.
//!
//! Radius schedule (pass i = 1, 2, …; α in (0, 1), `settings.alpha`): in d dimensions
//! r_i^d = r_1^d · Π_{j=1}^{i−1} (j + α)/(j + 1), with d = 2 for the surface map (the issue's
//! r_i² schedule) and d = 3 for volume maps (the volume a photon is gathered from shrinks by
//! the same factor). r_1 is `settings.radius` when given, else the radius that holds k photons
//! at the mean density of pass 1's map (half the `vpm` default cap).
//!
//! Every scattering event is stored (the `vpm-full` rule), so single scattering is exact
//! through refraction. Streams (rng.rs): pass p traces photons with tag [`pass_tag`]`(p)` =
//! p·2³² (a surface pass, when one is needed: plus [`SURFACE_PASS`]) and renders its camera
//! pass with seed [`pass_seed`]`(seed, p)` = `seed ^ (p << 40)`.
//!
//! [`SURFACE_PASS`]: crate::rng::SURFACE_PASS

use crate::control::Control;
use crate::error::Result;
use crate::integrators::photon_trace::PhotonMaps;
use crate::integrators::photon_trace::{trace_camera_maps, StoreMode};
use crate::integrators::settings::{Settings, Stats, VolumeEstimator};
use crate::integrators::tiles::render_tiles;
use crate::integrators::vpm::{default_volume_radius, Vpm, VpmParams};
use crate::photon_map::PHOTON_BYTES;
use crate::rng::{pass_seed, pass_tag};
use crate::scene::Scene;
use std::time::Instant;

/// r_i / r_1 for pass `i` (1-based) in `dim` dimensions with parameter `alpha`.
pub fn radius_ratio(i: u32, alpha: f64, dim: i32) -> f64 {
    let mut f = 1.0;
    for j in 1..i {
        f *= (j as f64 + alpha) / (j as f64 + 1.0);
    }
    f.powf(1.0 / dim as f64)
}

/// The photon maps of pass `pass` (1-based): `settings.volume_photons` volume photons with
/// tag [`pass_tag`]`(pass)`, the surface map from `settings.photons` of them (`trace_camera_maps`).
fn trace_pass(
    scene: &Scene,
    settings: &Settings,
    control: &Control,
    pass: u32,
) -> Result<PhotonMaps> {
    trace_camera_maps(scene, settings, StoreMode::All, pass_tag(pass), control)
}

/// The estimator of one pass's maps, before its radii are set.
fn pass_estimator<'a>(scene: &'a Scene, settings: &Settings, maps: &'a PhotonMaps) -> Vpm<'a> {
    Vpm::new(
        scene,
        maps,
        VpmParams::from_settings(settings, StoreMode::All),
    )
}

/// Pass 1's radius r_1 as a fraction of the `vpm` default radius, when `settings.radius`
/// is not given (the points' kernels; the beam's discs start at the `vpm` default itself).
const FIRST_RADIUS_FRACTION: f64 = 0.5;

/// Pass 1's radii r_1 [mm]: per medium and for the surface map. `settings.radius` when
/// given, else [`FIRST_RADIUS_FRACTION`] of the `vpm` default (k photons at the mean density
/// of pass 1's maps).
fn first_radii(
    scene: &Scene,
    settings: &Settings,
    maps: &PhotonMaps,
    vpm: &Vpm,
) -> (Vec<f64>, f64) {
    let vol = (0..scene.media.len())
        .map(|i| {
            settings.radius.unwrap_or(
                FIRST_RADIUS_FRACTION * default_volume_radius(scene, &maps.volume[i], settings.k),
            )
        })
        .collect();
    (
        vol,
        settings
            .surface_cap()
            .unwrap_or(FIRST_RADIUS_FRACTION * vpm.surface_radius),
    )
}

/// Render a band with probabilistic progressive photon mapping: passes
/// `settings.pass_index + 1 ..= settings.pass_index + settings.passes` of the schedule, each
/// of `settings.volume_photons` volume and `settings.photons` surface photons, averaged.
///
/// A pass depends only on (scene, settings without `pass_index`/`passes`, pass number), so
/// the mean of single-pass renders (`passes = 1`, `pass_index = p`) over p = 0..N−1 in pass
/// order equals the `passes = N` render. A render that starts after pass 1 without a fixed
/// `settings.radius` first traces pass 1's maps to find r_1 (and drops them): it costs one
/// more photon pass, not more memory.
pub fn render(scene: &Scene, settings: &Settings, control: &Control) -> Result<(Vec<f32>, Stats)> {
    // in range: Settings::validate bounds pass_index + passes by MAX_PASSES − 1 (settings.rs)
    let (first, last) = (
        settings.pass_index + 1,
        settings.pass_index + settings.passes,
    );
    let cam = &scene.camera;
    let mut sum = vec![0.0f64; cam.width * cam.height];
    let mut stats = Stats {
        integrator: "ppm".into(),
        bytes_per_photon: PHOTON_BYTES as u64,
        ..Stats::default()
    };
    let beam = settings.estimator() == VolumeEstimator::Beam;
    stats.estimator = settings.estimator().name().into();
    let mut r1: Option<(Vec<f64>, f64)> = None;
    if first > 1 && settings.radius.is_none() {
        // pilot: pass 1's maps give r_1, as in a render from pass 1
        let maps = trace_pass(scene, settings, control, 1)?;
        let vpm = pass_estimator(scene, settings, &maps);
        r1 = Some(first_radii(scene, settings, &maps, &vpm));
        stats.seconds_photons += maps.trace_seconds;
        stats.seconds_build += maps.build_seconds;
        stats.photon_map_bytes = maps.bytes() as u64;
        stats.extra.push((
            "pilot_photons".into(),
            (settings.volume_photons + settings.photons) as f64,
        ));
    }
    let mut last_radii = (Vec::new(), 0.0);
    for pass in first..=last {
        let maps = trace_pass(scene, settings, control, pass)?;
        stats.seconds_photons += maps.trace_seconds;
        stats.seconds_build += maps.build_seconds;
        stats.photons_emitted += maps.emitted;
        stats.photons_stored += maps.stored() as u64;
        stats.photon_map_bytes = stats.photon_map_bytes.max(maps.bytes() as u64);
        let mut vpm = pass_estimator(scene, settings, &maps);
        let (vol_r1, surf_r1) = r1
            .get_or_insert_with(|| first_radii(scene, settings, &maps, &vpm))
            .clone();
        let (fv, fs) = (
            radius_ratio(pass, settings.alpha, 3),
            radius_ratio(pass, settings.alpha, 2),
        );
        // the beam's discs blur only across the ray: they shrink like a 2-D kernel, from the
        // radius `bre` uses (settings.radius, else the vpm default itself)
        let vol_scale = match (beam, settings.radius) {
            (false, _) => fv,
            (true, Some(_)) => fs,
            (true, None) => fs / FIRST_RADIUS_FRACTION,
        };
        for (m, r) in vpm.media.iter_mut().zip(vol_r1.iter()) {
            m.radius = r * vol_scale;
        }
        vpm.surface_radius = surf_r1 * fs;
        vpm.fixed_radius = true;
        if beam {
            let t_beams = Instant::now();
            vpm.build_beams();
            stats.seconds_build += t_beams.elapsed().as_secs_f64();
        }
        let pass_settings = Settings {
            seed: pass_seed(settings.seed, pass),
            // the film continues its sub-pixel sequence where the previous pass stopped
            pass_index: pass - 1,
            ..*settings
        };
        let t0 = Instant::now();
        let (image, totals) = render_tiles(scene, &pass_settings, control, |ray, rng, sc| {
            vpm.radiance(ray, rng, sc)
        })?;
        stats.seconds_camera += t0.elapsed().as_secs_f64();
        stats.rays += totals.rays;
        for (s, v) in sum.iter_mut().zip(&image) {
            *s += *v as f64;
        }
        last_radii = (
            vpm.media.iter().map(|m| m.radius).collect(),
            vpm.surface_radius,
        );
        if beam {
            for (i, m) in vpm.media.iter().enumerate() {
                if scene.media[i].sigma_s > 0.0 {
                    let key = format!("radius_medium{i}_pass{pass}");
                    stats.extra.push((key, m.radius));
                }
            }
        }
    }
    let n = settings.passes as f64;
    let image = sum.iter().map(|s| (s / n) as f32).collect();
    stats.radius = last_radii.1;
    stats.extra.push(("passes".into(), n));
    stats.extra.push(("pass_first".into(), first as f64));
    stats
        .extra
        .push(("surface_radius_last".into(), last_radii.1));
    for (i, r) in last_radii.0.iter().enumerate() {
        if scene.media[i].sigma_s > 0.0 {
            stats.extra.push((format!("radius_medium{i}_last"), *r));
        }
    }
    Ok((image, stats))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radius_schedule_matches_its_product_form() {
        assert_eq!(radius_ratio(1, 0.7, 2), 1.0);
        // r_2² / r_1² = (1 + α)/2
        assert!((radius_ratio(2, 0.7, 2).powi(2) - 0.85).abs() < 1e-12);
        // r_3³ / r_1³ = (1 + α)/2 · (2 + α)/3
        assert!((radius_ratio(3, 0.5, 3).powi(3) - 0.75 * 2.5 / 3.0).abs() < 1e-12);
        // the radius shrinks like i^((α−1)/d) (Knaus & Zwicker): check the exponent at i = 10⁴
        let (a, b) = (radius_ratio(5000, 0.7, 2), radius_ratio(10000, 0.7, 2));
        let slope = (b / a).ln() / 2f64.ln();
        assert!((slope - (0.7 - 1.0) / 2.0).abs() < 1e-3, "{slope}");
    }
}
