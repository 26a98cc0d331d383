//! The reference for surface light transport: a brute-force path tracer for scenes of opaque
//! Lambertian surfaces and smooth dielectric shapes filled with clear (non-scattering,
//! possibly absorbing) media. At each diffuse vertex it samples one light by power (next-event
//! estimation with a shadow ray that passes index-matched boundaries) and continues along a
//! cosine-weighted direction; Russian roulette ends paths after three bounces with survival
//! probability min(β, 0.95). Area lights seen by camera rays or after a specular
//! (mismatched-boundary) event add their radiance; after a diffuse bounce they are already
//! counted by the light sample, so they add nothing (no double counting).
//!
//! Radiance crossing a refracting boundary is scaled by (η_i/η_t)² (η_i on the camera side):
//! radiance/η² is what is conserved along a ray, so a Lambertian surface inside glass looks
//! 1/η² as bright from air (times the Fresnel transmittance, sampled by roulette).

use super::direct::{check_clear_media, direct_irradiance, facing};
use super::settings::{Settings, Stats};
use super::tiles::{render_tiles, Scratch};
use super::transport::{cross, spawn};
use crate::control::Control;
use crate::error::Result;
use crate::geometry::Ray;
use crate::math::Frame;
use crate::rng::Stream;
use crate::sampling::cosine_hemisphere;
use crate::scene::{Boundary, Scene};
use std::f64::consts::PI;
use std::time::Instant;

/// Bounces after which Russian roulette may end a path.
const RR_DEPTH: u32 = 3;

/// Radiance arriving at the camera along `ray` (starting in the ambient medium).
pub fn radiance(
    scene: &Scene,
    ray: &Ray,
    max_depth: u32,
    rng: &mut Stream,
    scratch: &mut Scratch,
) -> f64 {
    let mut ray = *ray;
    let mut medium = scene.ambient_medium;
    let mut beta = 1.0;
    let mut l = 0.0;
    let mut count_emission = true;
    let mut bounces = 0;
    for _ in 0..max_depth {
        let hit = scene.intersect(&ray, f64::INFINITY);
        scratch.rays += 1;
        let t_hit = hit.map_or(f64::INFINITY, |h| h.t);
        let sigma_a = scene.media[medium as usize].sigma_a;
        if count_emission {
            if let Some((le, t)) = scene.emitted(&ray, t_hit) {
                l += beta * le * (-sigma_a * t).exp();
            }
        }
        let Some(hit) = hit else {
            break;
        };
        beta *= (-sigma_a * hit.t).exp();
        match scene.boundary(hit.shape) {
            Boundary::Dielectric { inside, outside } => {
                let c = cross(scene, &hit, ray.d, inside, outside);
                let d = c.choose(rng, &mut beta, &mut medium);
                if c.mismatched() {
                    count_emission = true;
                }
                ray = spawn(scene, &hit, d);
            }
            Boundary::Opaque { .. } => {
                let rho = scene.reflectance(&hit);
                if rho <= 0.0 {
                    break;
                }
                let n_f = facing(&hit, ray.d);
                l += beta * rho / PI * direct_irradiance(scene, &hit, n_f, medium, rng, scratch);
                // cosine-weighted bounce: f cos / pdf = ρ
                let d = Frame::from_axis(n_f).to_world(cosine_hemisphere(rng.uniform2()));
                beta *= rho;
                ray = spawn(scene, &hit, d);
                count_emission = false;
                bounces += 1;
                if bounces >= RR_DEPTH {
                    let q = beta.min(0.95);
                    if rng.uniform() >= q {
                        break;
                    }
                    beta /= q;
                }
            }
        }
        if beta == 0.0 {
            break;
        }
    }
    l
}

/// Render a band with the path tracer.
pub fn render(scene: &Scene, settings: &Settings, control: &Control) -> Result<(Vec<f32>, Stats)> {
    check_clear_media(scene, "path")?;
    let t0 = Instant::now();
    let (image, totals) = render_tiles(scene, settings, control, |ray, rng, scratch| {
        radiance(scene, ray, settings.max_depth, rng, scratch)
    })?;
    Ok((
        image,
        Stats {
            integrator: "path".into(),
            seconds_camera: t0.elapsed().as_secs_f64(),
            rays: totals.rays,
            ..Stats::default()
        },
    ))
}
