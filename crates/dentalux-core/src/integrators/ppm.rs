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
//! through refraction. Streams: pass p traces photons with tag p·2³² (surface pass: plus
//! [`SURFACE_PASS`]) and renders its camera pass with seed `seed ^ (p << 40)`.

use crate::control::Control;
use crate::error::{Error, Result};
use crate::integrators::photon_trace::{trace_photons_with, StoreMode, Targets, SURFACE_PASS};
use crate::integrators::render::{render_tiles, Settings, Stats};
use crate::integrators::vpm::{default_radius, Vpm, VpmParams};
use crate::photon_map::PHOTON_BYTES;
use crate::scene::Scene;
use std::time::Instant;

/// Most passes (the pass index must fit the stream tags below the surface-pass bit).
pub const MAX_PASSES: u32 = 4096;

/// r_i / r_1 for pass `i` (1-based) in `dim` dimensions with parameter `alpha`.
pub fn radius_ratio(i: u32, alpha: f64, dim: i32) -> f64 {
    let mut f = 1.0;
    for j in 1..i {
        f *= (j as f64 + alpha) / (j as f64 + 1.0);
    }
    f.powf(1.0 / dim as f64)
}

/// Render a band with probabilistic progressive photon mapping: `settings.passes` passes of
/// `settings.volume_photons` volume and `settings.photons` surface photons each.
pub fn render(scene: &Scene, settings: &Settings, control: &Control) -> Result<(Vec<f32>, Stats)> {
    if settings.passes > MAX_PASSES {
        return Err(Error::InvalidInput(format!(
            "settings.passes = {} is out of range: allowed [1, {MAX_PASSES}]",
            settings.passes
        )));
    }
    let (seed, band) = (settings.seed, settings.band);
    let vol_only = Targets {
        volume: true,
        surface: false,
    };
    let surf_only = Targets {
        volume: false,
        surface: true,
    };
    let cam = &scene.camera;
    let mut sum = vec![0.0f64; cam.width * cam.height];
    let mut stats = Stats {
        integrator: "ppm".into(),
        bytes_per_photon: PHOTON_BYTES as u64,
        ..Stats::default()
    };
    let mut r1: Option<(Vec<f64>, f64)> = None;
    let mut last = (Vec::new(), 0.0);
    for pass in 1..=settings.passes {
        let tag = (pass as u64) << 32;
        let mode = StoreMode::All;
        let mut maps = trace_photons_with(
            scene,
            settings.volume_photons,
            mode,
            vol_only,
            tag,
            seed,
            band,
            control,
        )?;
        let surf = trace_photons_with(
            scene,
            settings.photons,
            mode,
            surf_only,
            SURFACE_PASS | tag,
            seed,
            band,
            control,
        )?;
        maps.surface = surf.surface;
        stats.seconds_photons += maps.trace_seconds + surf.trace_seconds;
        stats.seconds_build += maps.build_seconds + surf.build_seconds;
        stats.photons_emitted += settings.volume_photons + settings.photons;
        stats.photons_stored += maps.stored() as u64;
        stats.photon_map_bytes = stats.photon_map_bytes.max(maps.bytes() as u64);
        let params = VpmParams {
            k: settings.k,
            radius: settings.radius,
            step: settings.step,
            mode,
            max_depth: settings.max_depth,
            ..VpmParams::default()
        };
        let mut vpm = Vpm::new(scene, &maps, params);
        let (vol_r1, surf_r1) = r1.get_or_insert_with(|| {
            let k = settings.k;
            let vol = (0..scene.media.len())
                .map(|i| {
                    settings
                        .radius
                        .unwrap_or(0.5 * default_radius(&maps.volume[i], k, false))
                })
                .collect();
            (vol, settings.radius.unwrap_or(0.5 * vpm.surface_radius))
        });
        let (fv, fs) = (
            radius_ratio(pass, settings.alpha, 3),
            radius_ratio(pass, settings.alpha, 2),
        );
        for (m, r) in vpm.media.iter_mut().zip(vol_r1.iter()) {
            m.radius = r * fv;
        }
        vpm.surface_radius = *surf_r1 * fs;
        vpm.fixed_radius = true;
        let pass_settings = Settings {
            seed: seed ^ ((pass as u64) << 40),
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
        last = (
            vpm.media.iter().map(|m| m.radius).collect(),
            vpm.surface_radius,
        );
    }
    let n = settings.passes as f64;
    let image = sum.iter().map(|s| (s / n) as f32).collect();
    stats.radius = last.1;
    stats.extra.push(("passes".into(), n));
    stats.extra.push(("surface_radius_last".into(), last.1));
    for (i, r) in last.0.iter().enumerate() {
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
