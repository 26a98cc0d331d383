//! BVH build and traversal speed on a large triangle mesh (run by benchmarks/render_cornell.py):
//! a UV sphere of about `--triangles` triangles (default 1 M) with radially jittered vertices,
//! built into a scene, then random rays from outside towards it, nearest-hit queries on one
//! thread and on all threads. Prints one JSON line.
//!
//!     cargo run --release -p dentalux-core --example bvh_bench -- [--triangles 1000000] [--rays 1000000]

use dentalux_core::camera::Camera;
use dentalux_core::geometry::bvh::Bvh;
use dentalux_core::geometry::mesh::TriangleMesh;
use dentalux_core::geometry::{Ray, Vec3};
use dentalux_core::lights::Light;
use dentalux_core::medium::Medium;
use dentalux_core::phase::PhaseFunction;
use dentalux_core::rng::Stream;
use dentalux_core::sampling::uniform_sphere;
use dentalux_core::scene::{Boundary, Geometry, Scene, ShapeInstance};
use dentalux_core::surface::Surface;
use rayon::prelude::*;
use std::time::Instant;

fn arg(name: &str, default: u64) -> u64 {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// CPU seconds this process has used (user + system, from /proc/self/stat; Linux only,
/// 0 elsewhere): on a shared machine the single-thread rate per CPU second is steadier than
/// per wall-clock second.
fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    // fields after the parenthesised command name; utime and stime are fields 14 and 15
    let rest = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = [11, 12]
        .iter()
        .filter_map(|&i| f.get(i)?.parse::<f64>().ok())
        .sum();
    ticks / 100.0 // USER_HZ is 100 on Linux
}

fn main() {
    let triangles = arg("--triangles", 1_000_000);
    let n_rays = arg("--rays", 1_000_000);
    // a UV sphere has 2 n_theta n_phi − 2 n_phi triangles; n_phi = 2 n_theta
    let n_theta = ((triangles as f64 / 4.0).sqrt().round() as usize).max(4);
    let mut mesh = TriangleMesh::uv_sphere(Vec3::ZERO, 10.0, n_theta, 2 * n_theta);
    let mut rng = Stream::new(1, 0, 0);
    for p in &mut mesh.positions {
        *p *= 1.0 + 0.02 * rng.uniform();
    }
    let n_tris = mesh.len();
    let bounds: Vec<_> = (0..n_tris).map(|i| mesh.triangle_bounds(i)).collect();
    let t0 = Instant::now();
    let bvh = Bvh::build(&bounds);
    let build_s = t0.elapsed().as_secs_f64();
    let nodes = bvh.node_count();
    let mut tests = 0u64;
    let mut prng = Stream::new(2, 0, 0);
    for _ in 0..10_000 {
        let o = uniform_sphere(prng.uniform2()) * 30.0;
        let t = uniform_sphere(prng.uniform2()) * (12.0 * prng.uniform());
        let r = Ray::new(o, t - o);
        bvh.nearest(&r, f64::INFINITY, |slot, tm| {
            tests += 1;
            let i = bvh.order()[slot as usize] as usize;
            mesh.intersect_triangle(i, r.o, r.d, tm).map(|h| h.t)
        });
    }
    let tests_per_ray = tests as f64 / 10_000.0;
    let t1 = Instant::now();
    let shape = ShapeInstance::new(
        "mesh",
        Geometry::Mesh(mesh),
        None,
        Boundary::Opaque { surface: 0 },
    )
    .expect("mesh");
    let scene = Scene::new(
        Camera::new(Vec3::new(0.0, 0.0, 40.0), Vec3::ZERO, Vec3::Y, 40.0, 8, 8).unwrap(),
        vec![Medium::new("", 0.0, 0.0, 1.0, PhaseFunction::Isotropic).unwrap()],
        vec![Surface::Lambertian { reflectance: 0.5 }],
        vec![shape],
        vec![Light::Point {
            position: Vec3::new(0.0, 30.0, 30.0),
            intensity: 1.0,
        }],
        0,
    )
    .expect("scene");
    let scene_s = t1.elapsed().as_secs_f64();
    // rays from a shell of radius 30 towards random points within radius 12
    let rays: Vec<Ray> = (0..n_rays)
        .map(|_| {
            let o = uniform_sphere(rng.uniform2()) * 30.0;
            let t = uniform_sphere(rng.uniform2()) * (12.0 * rng.uniform());
            Ray::new(o, t - o)
        })
        .collect();
    let t2 = Instant::now();
    let c2 = cpu_seconds();
    let hits_1: usize = rays
        .iter()
        .filter(|r| scene.intersect(r, f64::INFINITY).is_some())
        .count();
    let one_s = t2.elapsed().as_secs_f64();
    let one_cpu = cpu_seconds() - c2;
    let t3 = Instant::now();
    let hits_n: usize = rays
        .par_iter()
        .filter(|r| scene.intersect(r, f64::INFINITY).is_some())
        .count();
    let all_s = t3.elapsed().as_secs_f64();
    assert_eq!(hits_1, hits_n);
    println!(
        "{{\"triangles\": {n_tris}, \"bvh_nodes\": {nodes}, \"bvh_build_seconds\": {build_s:.3}, \
\"scene_build_seconds\": {scene_s:.3}, \"triangle_tests_per_ray\": {tests_per_ray:.2}, \"rays\": {n_rays}, \"hit_fraction\": {:.3}, \
\"rays_per_second_1_thread\": {:.0}, \"rays_per_cpu_second_1_thread\": {:.0}, \
\"rays_per_second_all_threads\": {:.0}, \"threads\": {}}}",
        hits_1 as f64 / n_rays as f64,
        n_rays as f64 / one_s,
        n_rays as f64 / one_cpu,
        n_rays as f64 / all_s,
        rayon::current_num_threads()
    );
}
