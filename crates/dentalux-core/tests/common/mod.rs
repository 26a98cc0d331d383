//! Scene builders shared by the integration tests: media, shapes, a camera, and the
//! disc-on-a-checker scene the volume integrators are judged on.
#![allow(dead_code)]

use dentalux_core::camera::Camera;
use dentalux_core::geometry::shapes::{Cylinder, Quad, Sphere};
use dentalux_core::geometry::Vec3;
use dentalux_core::lights::Light;
use dentalux_core::medium::Medium;
use dentalux_core::phase::PhaseFunction;
use dentalux_core::scene::{Boundary, Geometry, Scene, ShapeInstance};
use dentalux_core::surface::{Mapping, Surface};

pub fn medium(mua: f64, mus: f64, g: f64, n: f64) -> Medium {
    Medium::new(
        "",
        mua,
        mus,
        n,
        PhaseFunction::hg_with_isotropic(g, 0.0).unwrap(),
    )
    .unwrap()
}

pub fn air() -> Medium {
    medium(0.0, 0.0, 0.0, 1.0)
}

pub fn shape(g: Geometry, b: Boundary) -> ShapeInstance {
    ShapeInstance::new("shape", g, None, b).unwrap()
}

pub fn camera(pos: Vec3, at: Vec3, w: usize, h: usize) -> Camera {
    Camera::new(pos, at, Vec3::Z, 40.0, w, h).unwrap()
}

/// Disc of medium (dielectric `n`) a little above a checker ribbon, lit by an area light.
pub fn disc_scene(n: f64, w: usize, h: usize) -> Scene {
    disc_scene_height(n, w, h, 2.0)
}

/// [`disc_scene`] with a disc `height` mm thick.
pub fn disc_scene_height(n: f64, w: usize, h: usize, height: f64) -> Scene {
    let ribbon = shape(
        Geometry::Quad(Quad {
            corner: Vec3::new(-10.0, -10.0, 0.0),
            u: Vec3::new(20.0, 0.0, 0.0),
            v: Vec3::new(0.0, 20.0, 0.0),
        }),
        Boundary::Opaque { surface: 0 },
    );
    let disc = shape(
        Geometry::Cylinder(Cylinder {
            center: Vec3::new(0.0, 0.0, 0.05),
            axis: Vec3::Z,
            radius: 4.0,
            height,
        }),
        Boundary::Dielectric {
            inside: 1,
            outside: 0,
        },
    );
    let light = Light::Quad {
        corner: Vec3::new(-8.0, 8.0, 16.0),
        u: Vec3::new(16.0, 0.0, 0.0),
        v: Vec3::new(0.0, -16.0, 0.0),
        radiance: 1.0,
    };
    Scene::new(
        camera(Vec3::new(0.0, -11.0, 12.0), Vec3::new(0.0, 0.0, 1.0), w, h),
        vec![air(), medium(0.2, 3.0, 0.6, n)],
        vec![Surface::Checker {
            a: 0.8,
            b: 0.1,
            size: 2.0,
            mapping: Mapping::Xy,
        }],
        vec![ribbon, disc],
        vec![light],
        0,
    )
    .unwrap()
}

/// A sphere of one medium (n 1.5) around a sphere of another (n 1.4): enamel around dentin,
/// on a grey floor under an area light.
pub fn nested_spheres() -> Scene {
    let outer = shape(
        Geometry::Sphere(Sphere {
            center: Vec3::new(0.0, 0.0, 4.0),
            radius: 4.0,
        }),
        Boundary::Dielectric {
            inside: 1,
            outside: 0,
        },
    );
    let inner = shape(
        Geometry::Sphere(Sphere {
            center: Vec3::new(0.0, 0.0, 4.0),
            radius: 2.5,
        }),
        Boundary::Dielectric {
            inside: 2,
            outside: 1,
        },
    );
    let floor = shape(
        Geometry::Quad(Quad {
            corner: Vec3::new(-10.0, -10.0, 0.0),
            u: Vec3::new(20.0, 0.0, 0.0),
            v: Vec3::new(0.0, 20.0, 0.0),
        }),
        Boundary::Opaque { surface: 0 },
    );
    let light = Light::Quad {
        corner: Vec3::new(-8.0, 8.0, 18.0),
        u: Vec3::new(16.0, 0.0, 0.0),
        v: Vec3::new(0.0, -16.0, 0.0),
        radiance: 1.0,
    };
    Scene::new(
        camera(
            Vec3::new(0.0, -14.0, 12.0),
            Vec3::new(0.0, 0.0, 3.0),
            20,
            15,
        ),
        vec![
            air(),
            medium(0.1, 1.5, 0.3, 1.5),
            medium(0.4, 4.0, 0.7, 1.4),
        ],
        vec![Surface::Lambertian { reflectance: 0.5 }],
        vec![outer, inner, floor],
        vec![light],
        0,
    )
    .unwrap()
}

/// An unbounded medium around a point light of intensity 2 at the origin: `media[0]` fills
/// space and a far black speck is the scene's only shape (no photon travels 10⁴ mm).
pub fn point_in_infinite_medium(media: Vec<Medium>) -> Scene {
    let speck = shape(
        Geometry::Sphere(Sphere {
            center: Vec3::splat(1e4),
            radius: 1.0,
        }),
        Boundary::Opaque { surface: 0 },
    );
    Scene::new(
        camera(Vec3::new(0.0, -5.0, 0.0), Vec3::ZERO, 4, 4),
        media,
        vec![Surface::Black],
        vec![speck],
        vec![Light::Point {
            position: Vec3::ZERO,
            intensity: 2.0,
        }],
        0,
    )
    .unwrap()
}

/// Mean and standard error over independent estimates.
pub fn mean_se(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}
