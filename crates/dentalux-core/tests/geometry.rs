//! Geometry checks across modules: a finely tessellated sphere agrees with the analytic one
//! (hit distances and normals within the tessellation error), and the BVH over a mesh returns
//! exactly what brute force over its triangles returns.

use dentalux_core::camera::Camera;
use dentalux_core::geometry::mesh::TriangleMesh;
use dentalux_core::geometry::shapes::Sphere;
use dentalux_core::geometry::{Ray, Vec3};
use dentalux_core::integrators::transport::flight_reach;
use dentalux_core::lights::Light;
use dentalux_core::medium::Medium;
use dentalux_core::phase::PhaseFunction;
use dentalux_core::rng::Stream;
use dentalux_core::sampling::uniform_sphere;
use dentalux_core::scene::{Boundary, Geometry, Scene, ShapeInstance};
use dentalux_core::surface::Surface;
use std::f64::consts::PI;

fn scene_with(shapes: Vec<ShapeInstance>) -> Scene {
    Scene::new(
        Camera::new(Vec3::new(0.0, 0.0, 50.0), Vec3::ZERO, Vec3::Y, 40.0, 8, 8).unwrap(),
        vec![Medium::new("", 0.0, 0.0, 1.0, PhaseFunction::Isotropic).unwrap()],
        vec![Surface::Lambertian { reflectance: 0.5 }],
        shapes,
        vec![Light::Point {
            position: Vec3::new(0.0, 20.0, 20.0),
            intensity: 1.0,
        }],
        0,
    )
    .unwrap()
}

#[test]
fn fine_mesh_sphere_agrees_with_analytic_sphere() {
    let (c, r) = (Vec3::new(1.0, -2.0, 0.5), 3.0);
    let (nt, np) = (200, 400);
    let mesh = TriangleMesh::uv_sphere(c, r, nt, np);
    let dielectric = Boundary::Dielectric {
        inside: 0,
        outside: 0,
    };
    let scene = scene_with(vec![ShapeInstance::new(
        "m",
        Geometry::Mesh(mesh),
        None,
        dielectric,
    )
    .unwrap()]);
    let sphere = Sphere {
        center: c,
        radius: r,
    };
    // tessellation error: a facet spanning Δθ × Δφ lies at most r(1 − cos(half its diagonal))
    // inside the sphere; along a ray at incidence θ that costs sagitta / cos θ in distance
    let (dt, dp) = (PI / nt as f64, 2.0 * PI / np as f64);
    let delta = dt.max(dp);
    let sagitta = r * (1.0 - (0.5 * (dt * dt + dp * dp).sqrt()).cos());
    let mut rng = Stream::new(3, 0, 0);
    let mut checked = 0;
    for _ in 0..20_000 {
        let o = c + uniform_sphere(rng.uniform2()) * 10.0;
        // aim at a random point of the sphere's disc seen from o
        let target = c + uniform_sphere(rng.uniform2()) * (r * 0.95);
        let ray = Ray::new(o, target - o);
        let (Some(a), Some(m)) = (
            sphere.intersect(ray.o, ray.d, f64::INFINITY),
            scene.intersect(&ray, f64::INFINITY),
        ) else {
            continue;
        };
        let cos = -(a.n).dot(ray.d);
        if cos < 0.2 {
            continue; // near-grazing: distance error is unbounded by construction
        }
        checked += 1;
        assert!(
            m.t >= a.t - 1e-9 && m.t - a.t <= sagitta / cos + 1e-9,
            "mesh t {} vs sphere t {} (sagitta {sagitta}, cos {cos})",
            m.t,
            a.t
        );
        // a facet normal tilts from the sphere normal by at most about the facet's angular size
        let angle = m.n.dot(a.n).clamp(-1.0, 1.0).acos();
        assert!(
            angle <= delta,
            "normal off by {angle} rad (facet {delta}) at {} n {} vs {}",
            m.p - c,
            m.n,
            a.n
        );
    }
    assert!(checked > 10_000);
}

/// A bumpy, self-occluding mesh: a 5 mm sphere with radially displaced vertices.
fn bumpy_sphere(rng: &mut Stream) -> TriangleMesh {
    let mut mesh = TriangleMesh::uv_sphere(Vec3::ZERO, 5.0, 60, 120);
    for p in &mut mesh.positions {
        *p *= 1.0 + 0.3 * rng.uniform();
    }
    mesh
}

fn opaque_mesh_scene(mesh: TriangleMesh) -> Scene {
    scene_with(vec![ShapeInstance::new(
        "m",
        Geometry::Mesh(mesh),
        None,
        Boundary::Opaque { surface: 0 },
    )
    .unwrap()])
}

#[test]
fn bvh_over_a_mesh_equals_brute_force() {
    let mut rng = Stream::new(9, 0, 0);
    let tris = bumpy_sphere(&mut rng);
    let scene = opaque_mesh_scene(tris.clone());
    assert_eq!(scene.primitive_count(), tris.len());
    for i in 0..5_000 {
        let o = uniform_sphere(rng.uniform2()) * (4.0 + 6.0 * rng.uniform());
        let ray = Ray::new(o, uniform_sphere(rng.uniform2()));
        let t_max = if i % 2 == 0 { f64::INFINITY } else { 3.0 };
        let brute = (0..tris.len())
            .filter_map(|k| tris.intersect_triangle(k, ray.o, ray.d, t_max).map(|h| h.t))
            .fold(f64::INFINITY, f64::min);
        let got = scene.intersect(&ray, t_max).map_or(f64::INFINITY, |h| h.t);
        assert_eq!(got, brute);
        assert_eq!(scene.occluded(&ray, t_max), brute.is_finite());
    }
}

#[test]
fn a_flight_searched_to_its_collision_sees_what_a_search_to_infinity_sees() {
    // the photon tracer and volpath search the BVH only up to the sampled collision
    // (`transport::flight_reach`): the face they find must be the one an unbounded search
    // finds whenever it lies before the collision, and none otherwise
    let mut rng = Stream::new(4, 0, 0);
    let scene = opaque_mesh_scene(bumpy_sphere(&mut rng));
    let (mut before, mut beyond) = (0, 0);
    for _ in 0..20_000 {
        let o = uniform_sphere(rng.uniform2()) * (4.5 * rng.uniform());
        let ray = Ray::new(o, uniform_sphere(rng.uniform2()));
        let s = -rng.uniform_open0().ln() * 5.0;
        let full = scene
            .intersect(&ray, f64::INFINITY)
            .expect("inside a closed mesh");
        let capped = scene.intersect(&ray, flight_reach(s));
        if full.t <= s {
            before += 1;
            let c = capped.expect("a face before the collision is found");
            assert_eq!((c.t.to_bits(), c.shape), (full.t.to_bits(), full.shape));
        } else if full.t > flight_reach(s) {
            beyond += 1;
            assert!(capped.is_none());
        }
        // a face exactly at the collision is a boundary (the tie `s < t_hit`)
        let at = scene
            .intersect(&ray, flight_reach(full.t))
            .expect("face at s");
        assert_eq!(at.t.to_bits(), full.t.to_bits());
    }
    assert!(before > 2_000 && beyond > 2_000, "{before} {beyond}");
}

/// `Scene::clearance` is a lower bound on the distance to every surface: no ray from a
/// point meets a surface within it (analytic shapes, one of them transformed), and it is 0
/// where the scene holds a mesh.
#[test]
fn clearance_is_a_lower_bound_with_shapes_and_meshes() {
    use dentalux_core::geometry::shapes::{Cylinder, Quad};
    use dentalux_core::geometry::transform::Transform;
    let dielectric = Boundary::Dielectric {
        inside: 0,
        outside: 0,
    };
    let opaque = Boundary::Opaque { surface: 0 };
    let cylinder = Geometry::Cylinder(Cylinder {
        center: Vec3::new(-3.0, 0.0, 0.0),
        axis: Vec3::Z,
        radius: 2.0,
        height: 1.5,
    });
    let tilted = Transform::from_rows(
        "t",
        [
            [0.9, -0.4, 0.0, 3.0],
            [0.4, 0.9, 0.3, 0.0],
            [0.0, 0.0, 1.2, 0.5],
            [0.0, 0.0, 0.0, 1.0],
        ],
    )
    .unwrap();
    let sphere = Geometry::Sphere(Sphere {
        center: Vec3::ZERO,
        radius: 1.5,
    });
    let floor = Geometry::Quad(Quad {
        corner: Vec3::new(-10.0, -10.0, -1.0),
        u: Vec3::new(20.0, 0.0, 0.0),
        v: Vec3::new(0.0, 20.0, 0.0),
    });
    let scene = scene_with(vec![
        ShapeInstance::new("c", cylinder, None, dielectric).unwrap(),
        ShapeInstance::new("s", sphere.clone(), Some(tilted), dielectric).unwrap(),
        ShapeInstance::new("q", floor, None, opaque).unwrap(),
    ]);
    let mut rng = Stream::new(5, 0, 0);
    let mut positive = 0;
    for _ in 0..300 {
        let p = Vec3::new(
            rng.uniform() * 12.0 - 6.0,
            rng.uniform() * 6.0 - 3.0,
            rng.uniform() * 4.0 - 1.5,
        );
        let c = scene.clearance(p);
        assert!(c >= 0.0);
        positive += (c > 0.0) as usize;
        for _ in 0..200 {
            let ray = Ray::new(p, uniform_sphere(rng.uniform2()));
            assert!(scene.intersect(&ray, flight_reach(c)).is_none(), "{p}: {c}");
        }
    }
    assert!(positive > 250, "{positive}");
    let mesh = TriangleMesh::uv_sphere(Vec3::new(5.0, 5.0, 5.0), 1.0, 8, 16);
    let with_mesh = scene_with(vec![
        ShapeInstance::new("s", sphere, None, dielectric).unwrap(),
        ShapeInstance::new("m", Geometry::Mesh(mesh), None, dielectric).unwrap(),
    ]);
    // outside the grid over the media: no bound; inside the faceted ball, which lies
    // within its sphere (vertices on it): below the sphere's distance, and no surface nearer
    assert_eq!(with_mesh.clearance(Vec3::new(20.0, 0.0, 0.0)), 0.0);
    let centre = Vec3::new(5.0, 5.0, 5.0);
    for _ in 0..2000 {
        let p = centre + uniform_sphere(rng.uniform2()) * 0.99 * rng.uniform();
        let c = with_mesh.clearance(p);
        assert!(c <= 1.0 - (p - centre).length(), "{c} at {p}");
        for _ in 0..20 {
            let ray = Ray::new(p, uniform_sphere(rng.uniform2()));
            assert!(
                with_mesh.intersect(&ray, flight_reach(c)).is_none(),
                "{p}: {c}"
            );
        }
    }
    // deep inside, the bound is the Chebyshev one to the facets' boxes (at least 1/√3 of
    // the maximum-norm distance, less a few voxels)
    let c = with_mesh.clearance(centre);
    assert!(
        c > 0.3,
        "the centre of a ball of radius 1 (16 x 8 facets): {c}"
    );
}
