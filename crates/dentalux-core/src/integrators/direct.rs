//! Direct light at an opaque surface, shared by the surface integrators `path` and `pm`:
//! next-event estimation of the irradiance with a shadow ray through index-matched boundaries,
//! the normal facing the viewer, and the check that a scene's media are clear (these
//! integrators take absorption by Beer–Lambert along each segment, no scattering).

use super::tiles::Scratch;
use super::transport::straight_transmittance;
use crate::error::{Error, Result};
use crate::geometry::{offset_origin, Hit, Vec3};
use crate::rng::Stream;
use crate::scene::{Boundary, Scene};

/// Refuse scenes whose ambient or dielectric media scatter: `integrator` handles clear media
/// only (absorption by Beer–Lambert along each segment).
pub fn check_clear_media(scene: &Scene, integrator: &str) -> Result<()> {
    let mut used = vec![scene.ambient_medium];
    for s in scene.shapes() {
        if let Boundary::Dielectric { inside, outside } = s.boundary {
            used.push(inside);
            used.push(outside);
        }
    }
    for m in used {
        let medium = &scene.media[m as usize];
        if medium.sigma_s > 0.0 {
            return Err(Error::InvalidInput(format!(
                "settings.integrator = \"{integrator}\" renders clear media only, but media[{m}] scatters (mus = {} 1/mm): use \"vpm\" or \"volpath\"",
                medium.sigma_s
            )));
        }
    }
    Ok(())
}

/// The normal of `hit` turned against the travel direction `d` (the side being lit/seen).
#[inline]
pub fn facing(hit: &Hit, d: Vec3) -> Vec3 {
    if d.dot(hit.n) < 0.0 {
        hit.n
    } else {
        -hit.n
    }
}

/// One-sample estimate of the irradiance at an opaque `hit` on the side of `n_f` by next-event
/// estimation [radiance units × sr]: pick a light by power, sample it, test visibility
/// through index-matched boundaries (Beer–Lambert in clear media). Reflected radiance is ρ/π
/// times this.
#[inline]
pub fn direct_irradiance(
    scene: &Scene,
    hit: &Hit,
    n_f: Vec3,
    medium: u32,
    rng: &mut Stream,
    scratch: &mut Scratch,
) -> f64 {
    let (li, p_light) = scene.pick_light(rng.uniform());
    let u = rng.uniform2();
    let Some(ls) = scene.lights[li].sample_li(hit.p, u) else {
        return 0.0;
    };
    let cos = ls.wi.dot(n_f);
    if cos <= 0.0 {
        return 0.0;
    }
    let o = offset_origin(hit.p, hit.n, ls.wi, scene.eps);
    scratch.rays += 1;
    // stop short of the light point: a light lying on a wall must not be shadowed by it
    let tr = straight_transmittance(scene, o, ls.wi, ls.dist - 2.0 * scene.eps, medium);
    ls.value * cos * tr / p_light
}
