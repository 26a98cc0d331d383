//! The scene for one band, as plain data filled by the binding: camera, media, surface
//! materials, shapes with their boundaries, lights — plus the BVH over every primitive.
//!
//! Ray offsetting: rays leaving a surface start at p ± n·[`Scene::eps`], with
//! eps = 1e-7 × (largest |coordinate| of the scene bounds + 1 mm): about 10⁹ times the f64
//! rounding of a coordinate, and far below any feature size a dental scene has.

use crate::camera::Camera;
use crate::error::{check_positive, Error, Result};
use crate::geometry::bvh::Bvh;
use crate::geometry::clearance_grid::ClearanceGrid;
use crate::geometry::mesh::{distance_to_corners, intersect_corners, Topology, TriangleMesh};
use crate::geometry::shapes::{BoxShape, Cylinder, LocalHit, Quad, Sphere};
use crate::geometry::transform::Transform;
use crate::geometry::{Aabb, Hit, Ray, Vec3};
use crate::lights::Light;
use crate::medium::Medium;
use crate::surface::Surface;
use std::sync::Arc;

/// What a closed shape separates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Boundary {
    /// An opaque Lambertian surface (both sides reflect).
    Opaque {
        /// Index into `scene.surfaces`.
        surface: u32,
    },
    /// A smooth dielectric interface between two media (closed shapes only).
    Dielectric {
        /// Index into `scene.media` of the medium inside the shape.
        inside: u32,
        /// Index into `scene.media` of the medium outside (the side the normal points to).
        outside: u32,
    },
}

/// The geometry of one shape.
#[derive(Debug, Clone, PartialEq)]
pub enum Geometry {
    /// A sphere (object space).
    Sphere(Sphere),
    /// A parallelogram (object space; open).
    Quad(Quad),
    /// An axis-aligned box (object space).
    Box(BoxShape),
    /// A capped cylinder (object space).
    Cylinder(Cylinder),
    /// A triangle mesh, in world space.
    Mesh(TriangleMesh),
}

/// A shape in the scene: geometry, optional object-to-world transform, boundary.
#[derive(Debug, Clone, PartialEq)]
pub struct ShapeInstance {
    /// The geometry.
    pub geometry: Geometry,
    /// Object-to-world transform (`None` for identity; meshes are baked to world space).
    pub transform: Option<Transform>,
    /// What the surface separates.
    pub boundary: Boundary,
    /// Millimetres per unit of uv along u and v (for textures in mm).
    pub uv_scale: [f64; 2],
    /// Whether the surface encloses a volume (all but quads and open meshes).
    closed: bool,
}

impl ShapeInstance {
    /// A validated shape; `field` names it in errors (e.g. `shapes[2]`). A mesh's transform
    /// is applied to its positions here, and an inward-wound closed mesh is flipped.
    pub fn new(
        field: &str,
        geometry: Geometry,
        transform: Option<Transform>,
        boundary: Boundary,
    ) -> Result<Self> {
        let positive = |k: &str, v: f64| check_positive(&format!("{field}.{k}"), v, "mm");
        let finite = |k: &str, v: Vec3| {
            if v.is_finite() {
                Ok(())
            } else {
                Err(Error::InvalidInput(format!(
                    "{field}.{k} must be finite, got {v}"
                )))
            }
        };
        let dielectric = matches!(boundary, Boundary::Dielectric { .. });
        let mut geometry = geometry;
        // an identity transform (as the scene files give for untransformed shapes) would
        // cost two matrix products per intersection for nothing
        let mut transform = transform.filter(|t| !t.is_identity());
        let uv_scale = match &mut geometry {
            Geometry::Sphere(s) => {
                finite("center", s.center)?;
                positive("radius", s.radius)?;
                s.uv_scale()
            }
            Geometry::Quad(q) => {
                finite("corner", q.corner)?;
                finite("u", q.u)?;
                finite("v", q.v)?;
                if q.area().is_nan() || q.area() <= 0.0 {
                    return Err(Error::InvalidInput(format!(
                        "{field}: u and v must be non-zero and not parallel"
                    )));
                }
                if dielectric {
                    return Err(Error::InvalidInput(format!(
                        "{field}: a quad is open, so its boundary must be opaque, not dielectric"
                    )));
                }
                q.uv_scale()
            }
            Geometry::Box(b) => {
                finite("min", b.min)?;
                finite("max", b.max)?;
                for (k, lo, hi) in [
                    ("x", b.min.x, b.max.x),
                    ("y", b.min.y, b.max.y),
                    ("z", b.min.z, b.max.z),
                ] {
                    if hi <= lo {
                        return Err(Error::InvalidInput(format!(
                            "{field}.max.{k} = {hi} must exceed {field}.min.{k} = {lo}"
                        )));
                    }
                }
                b.uv_scale()
            }
            Geometry::Cylinder(c) => {
                finite("center", c.center)?;
                positive("radius", c.radius)?;
                positive("height", c.height)?;
                c.axis = crate::lights::unit(&format!("{field}.axis"), c.axis)?;
                c.uv_scale()
            }
            Geometry::Mesh(m) => {
                if m.is_empty() {
                    return Err(Error::InvalidInput(format!("{field}.triangles is empty")));
                }
                m.check_indices(&format!("{field}."))?;
                let nv = m.positions.len();
                for (i, p) in m.positions.iter().enumerate() {
                    finite(&format!("positions[{i}]"), *p)?;
                }
                if let Some(uvs) = &m.uvs {
                    if uvs.len() != nv {
                        return Err(Error::InvalidInput(format!(
                            "{field}.uvs has {} entries, positions has {nv}",
                            uvs.len()
                        )));
                    }
                }
                if let Some(t) = transform.take() {
                    for p in &mut m.positions {
                        *p = t.point(*p);
                    }
                }
                if dielectric {
                    match m.topology() {
                        Topology::Closed => {}
                        Topology::Open { bad_edges } => {
                            return Err(Error::InvalidInput(format!(
                                "{field}: a dielectric boundary needs a closed mesh, but {bad_edges} edges are not shared by exactly two triangles"
                            )))
                        }
                        Topology::Inconsistent { bad_edges } => {
                            return Err(Error::InvalidInput(format!(
                                "{field}: a dielectric boundary needs a consistently oriented mesh, but {bad_edges} edges are traversed twice in the same direction"
                            )))
                        }
                    }
                    if m.signed_volume() < 0.0 {
                        m.flip();
                    }
                }
                [1.0, 1.0]
            }
        };
        let s = transform.map_or(1.0, |t| t.scale());
        let closed = match &geometry {
            Geometry::Quad(_) => false,
            Geometry::Mesh(m) => dielectric || m.topology() == Topology::Closed,
            _ => true,
        };
        Ok(Self {
            geometry,
            transform,
            boundary,
            uv_scale: [uv_scale[0] * s, uv_scale[1] * s],
            closed,
        })
    }

    /// Number of primitives (1, or the triangle count of a mesh).
    pub fn primitive_count(&self) -> usize {
        match &self.geometry {
            Geometry::Mesh(m) => m.len(),
            _ => 1,
        }
    }

    /// A lower bound on the distance from world point `p` to this shape's surface [mm], for
    /// the analytic shapes; `None` for meshes.
    pub fn clearance(&self, p: Vec3) -> Option<f64> {
        let q = self.transform.map_or(p, |t| t.inv_point(p));
        let local = match &self.geometry {
            Geometry::Sphere(s) => s.clearance(q),
            Geometry::Quad(s) => s.clearance(q),
            Geometry::Box(s) => s.clearance(q),
            Geometry::Cylinder(s) => s.clearance(q),
            Geometry::Mesh(_) => return None,
        };
        Some(self.transform.map_or(local, |t| local * t.min_stretch()))
    }

    /// World bounds of primitive `prim`.
    pub fn primitive_bounds(&self, prim: usize) -> Aabb {
        let local = match &self.geometry {
            Geometry::Sphere(s) => s.bounds(),
            Geometry::Quad(q) => q.bounds(),
            Geometry::Box(b) => b.bounds(),
            Geometry::Cylinder(c) => c.bounds(),
            Geometry::Mesh(m) => return m.triangle_bounds(prim),
        };
        match &self.transform {
            Some(t) => t.bounds(&local),
            None => local,
        }
    }

    /// World bounds of the whole shape (all its primitives).
    pub fn bounds(&self) -> Aabb {
        (0..self.primitive_count())
            .map(|k| self.primitive_bounds(k))
            .fold(Aabb::EMPTY, |a, b| a.union(&b))
    }

    /// Intersect primitive `prim` with a world ray; world hit (shape index left 0).
    #[inline]
    pub fn intersect_primitive(&self, prim: usize, ray: &Ray, t_max: f64) -> Option<Hit> {
        let (o, d) = match &self.transform {
            Some(t) => (t.inv_point(ray.o), t.inv_vector(ray.d)),
            None => (ray.o, ray.d),
        };
        let h: LocalHit = match &self.geometry {
            Geometry::Sphere(s) => s.intersect(o, d, t_max),
            Geometry::Quad(q) => q.intersect(o, d, t_max),
            Geometry::Box(b) => b.intersect(o, d, t_max),
            Geometry::Cylinder(c) => c.intersect(o, d, t_max),
            Geometry::Mesh(m) => m.intersect_triangle(prim, o, d, t_max),
        }?;
        let n = match &self.transform {
            Some(t) => t.normal(h.n),
            None => h.n.normalize(),
        };
        Some(Hit {
            t: h.t,
            p: ray.at(h.t),
            n,
            uv: h.uv,
            shape: 0,
        })
    }

    /// Whether the shape is closed (everything but quads and open meshes).
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    /// Whether world point `p` lies inside this closed shape (false for open shapes).
    pub fn contains(&self, p: Vec3) -> bool {
        let q = self.transform.map_or(p, |t| t.inv_point(p));
        match &self.geometry {
            Geometry::Sphere(s) => s.contains(q),
            Geometry::Box(b) => b.contains(q),
            Geometry::Cylinder(c) => c.contains(q),
            Geometry::Quad(_) => false,
            Geometry::Mesh(m) => self.closed && m.encloses(q),
        }
    }
}

/// A primitive of the BVH: a mesh triangle with its corners inline (one cache line per
/// test instead of four dependent loads), or a whole analytic shape.
#[derive(Debug, Clone, Copy)]
enum Prim {
    Triangle {
        corners: [Vec3; 3],
        shape: u32,
        index: u32,
    },
    Shape {
        shape: u32,
    },
}

/// Most shapes for which [`Scene::clearance`] scans them all (the Fig. 3 scene has four).
pub const CLEARANCE_SHAPES: usize = 16;

/// The band-independent part of a scene: the shapes, their BVH and its primitives. Shared
/// (behind an `Arc`) by every band's [`Scene`], so a multi-band render builds it once.
#[derive(Debug)]
struct Built {
    shapes: Vec<ShapeInstance>,
    /// Whether [`Scene::clearance`] can bound distances (a few analytic shapes).
    clearance: bool,
    /// BVH primitives in slot order (a leaf's primitives are contiguous).
    prims: Vec<Prim>,
    bvh: Bvh,
    /// Distance bounds on a voxel grid over the media, for scenes with meshes
    /// ([`clearance_grid`]).
    grid: Option<ClearanceGrid>,
    /// Per medium index, the shapes a walk in that medium can only meet ([`enclosures`]).
    enclosures: Vec<Option<Box<[u32]>>>,
}

/// The least of `shapes[i]`'s clearances from `p` over `which`, shrunk by a margin far above
/// the intersection routines' rounding (0 where a shape has none).
#[inline]
fn clearance_of(shapes: &[ShapeInstance], p: Vec3, which: impl Iterator<Item = u32>) -> f64 {
    shrink(
        which
            .map(|i| shapes[i as usize].clearance(p).unwrap_or(0.0))
            .fold(f64::INFINITY, f64::min),
    )
}

/// A distance bound less a margin far above the intersection routines' rounding.
#[inline]
fn shrink(d: f64) -> f64 {
    (d * (1.0 - 1e-9) - 1e-9).max(0.0)
}

/// The clearance grid of a scene with meshes (`None` without): over the shapes that hold
/// media, where walks scatter, with every primitive's box marked, except that an analytic
/// shape whose box covers more than a 64th of the region bounds it through its own
/// clearance (a box around the scene would otherwise mark every voxel).
fn clearance_grid(shapes: &[ShapeInstance], bvh: &Bvh, prims: &[Prim]) -> Option<ClearanceGrid> {
    if !shapes
        .iter()
        .any(|s| matches!(s.geometry, Geometry::Mesh(_)))
    {
        return None;
    }
    let region = shapes
        .iter()
        .filter(|s| matches!(s.boundary, Boundary::Dielectric { .. }))
        .map(ShapeInstance::bounds)
        .fold(Aabb::EMPTY, |a, b| a.union(&b));
    let volume = |b: &Aabb| {
        let e = (b.max.min(region.max) - b.min.max(region.min)).max(Vec3::ZERO);
        e.x * e.y * e.z
    };
    let large = |s: u32| {
        let s = &shapes[s as usize];
        s.clearance(Vec3::ZERO).is_some() && volume(&s.bounds()) > volume(&region) / 64.0
    };
    let marked = prims.iter().filter_map(|p| match *p {
        Prim::Triangle { shape, index, .. } => {
            Some(shapes[shape as usize].primitive_bounds(index as usize))
        }
        Prim::Shape { shape } => (!large(shape)).then(|| shapes[shape as usize].bounds()),
    });
    let exact = |p: Vec3, reach: f64| {
        bvh.distance_bound(p, reach, |slot| match prims[slot as usize] {
            Prim::Triangle {
                corners: [a, b, c], ..
            } => distance_to_corners(a, b, c, p),
            Prim::Shape { shape } => shapes[shape as usize].clearance(p).unwrap_or(0.0),
        })
    };
    let mut grid = ClearanceGrid::build(region, marked, exact)?;
    for (i, s) in shapes.iter().enumerate() {
        if large(i as u32) {
            grid.limit(|c| s.clearance(c).unwrap_or(0.0));
        }
    }
    Some(grid)
}

/// Per medium index: the analytic shapes that hold the medium inside, when they are all a
/// walk in it can meet first. That is so when the medium is inside those shapes only, is
/// nobody's outside nor the camera's, and no other shape's box touches theirs: a walk in
/// the medium is then inside one of them, and every point of its flight up to that shape's
/// surface lies in the shape's box, where nothing else is. `None` where any of that fails
/// (meshes included: their triangles want the BVH).
fn enclosures(shapes: &[ShapeInstance], ambient: u32) -> Vec<Option<Box<[u32]>>> {
    let bounds: Vec<Aabb> = shapes.iter().map(ShapeInstance::bounds).collect();
    // closed boxes, widened by far more than any rounding of the bounds: touching counts
    let touch = |a: &Aabb, b: &Aabb| {
        let pad = 1e-6 * (1.0 + a.max.abs().max_element() + b.max.abs().max_element());
        (0..3).all(|i| a.min[i] <= b.max[i] + pad && b.min[i] <= a.max[i] + pad)
    };
    let media = shapes
        .iter()
        .filter_map(|s| match s.boundary {
            Boundary::Dielectric { inside, outside } => Some(inside.max(outside) as usize + 1),
            Boundary::Opaque { .. } => None,
        })
        .max()
        .unwrap_or(0);
    (0..media as u32)
        .map(|m| {
            if m == ambient {
                return None;
            }
            let mut own = Vec::new();
            for (i, s) in shapes.iter().enumerate() {
                if let Boundary::Dielectric { inside, outside } = s.boundary {
                    if outside == m {
                        return None;
                    }
                    if inside == m {
                        own.push(i as u32);
                    }
                }
            }
            let alone = |i: usize| {
                !matches!(shapes[i].geometry, Geometry::Mesh(_))
                    && (0..shapes.len()).all(|j| j == i || !touch(&bounds[i], &bounds[j]))
            };
            (!own.is_empty() && own.iter().all(|&i| alone(i as usize)))
                .then(|| own.into_boxed_slice())
        })
        .collect()
}

/// Everything a band's render needs.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The camera.
    pub camera: Camera,
    /// Media at this band (index 0 is usually air).
    pub media: Vec<Medium>,
    /// Surface materials.
    pub surfaces: Vec<Surface>,
    /// Lights.
    pub lights: Vec<Light>,
    /// Index into `media` of the medium the camera is in.
    pub ambient_medium: u32,
    /// Ray offset [mm] (see the module docs).
    pub eps: f64,
    built: Arc<Built>,
    light_cdf: Vec<f64>,
}

impl Scene {
    /// Assemble and validate a scene; builds the BVH.
    pub fn new(
        camera: Camera,
        media: Vec<Medium>,
        surfaces: Vec<Surface>,
        shapes: Vec<ShapeInstance>,
        lights: Vec<Light>,
        ambient_medium: u32,
    ) -> Result<Self> {
        let light_cdf = check_band(&media, &surfaces, &shapes, &lights, ambient_medium)?;
        for (i, s) in shapes.iter().enumerate() {
            if matches!(s.boundary, Boundary::Opaque { .. }) && s.contains(camera.position) {
                return Err(Error::InvalidInput(format!(
                    "camera.position lies inside shapes[{i}], which is opaque: the camera would see nothing"
                )));
            }
        }
        let mut prims = Vec::new();
        let mut bounds = Vec::new();
        for (i, s) in shapes.iter().enumerate() {
            for k in 0..s.primitive_count() {
                prims.push((i as u32, k as u32));
                bounds.push(s.primitive_bounds(k));
            }
        }
        let bvh = Bvh::build(&bounds);
        // store primitives in the BVH's slot order
        let prims: Vec<Prim> = bvh
            .order()
            .iter()
            .map(|&p| {
                let (s, k) = prims[p as usize];
                match &shapes[s as usize].geometry {
                    Geometry::Mesh(m) => Prim::Triangle {
                        corners: m.corners(k as usize),
                        shape: s,
                        index: k,
                    },
                    _ => Prim::Shape { shape: s },
                }
            })
            .collect();
        let clearance = shapes.len() <= CLEARANCE_SHAPES
            && shapes.iter().all(|s| s.clearance(Vec3::ZERO).is_some());
        let built = Arc::new(Built {
            enclosures: enclosures(&shapes, ambient_medium),
            grid: clearance_grid(&shapes, &bvh, &prims),
            shapes,
            clearance,
            prims,
            bvh,
        });
        Ok(Self {
            eps: ray_offset(&built.bvh, &camera, &lights),
            camera,
            media,
            surfaces,
            lights,
            ambient_medium,
            built,
            light_cdf,
        })
    }

    /// The same shapes, BVH and camera with another band's media, surfaces and lights,
    /// validated as in [`Scene::new`] (lights are not in the BVH, so they may differ freely).
    pub fn with_band(
        &self,
        media: Vec<Medium>,
        surfaces: Vec<Surface>,
        lights: Vec<Light>,
    ) -> Result<Self> {
        let light_cdf = check_band(
            &media,
            &surfaces,
            self.shapes(),
            &lights,
            self.ambient_medium,
        )?;
        Ok(Self {
            eps: ray_offset(&self.built.bvh, &self.camera, &lights),
            camera: self.camera,
            media,
            surfaces,
            lights,
            ambient_medium: self.ambient_medium,
            built: Arc::clone(&self.built),
            light_cdf,
        })
    }

    /// Whether `other` shares this scene's shapes and BVH (built once for both).
    pub fn shares_geometry(&self, other: &Scene) -> bool {
        Arc::ptr_eq(&self.built, &other.built)
    }

    /// The shapes.
    #[inline]
    pub fn shapes(&self) -> &[ShapeInstance] {
        &self.built.shapes
    }

    /// Nearest surface hit with t in (0, t_max).
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f64) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        self.built.bvh.nearest(ray, t_max, |slot, tm| {
            let h = match self.built.prims[slot as usize] {
                Prim::Triangle {
                    corners: [a, b, c],
                    shape,
                    index,
                } => {
                    let (t, b1, b2) = intersect_corners(a, b, c, ray.o, ray.d, tm)?;
                    let uv = match &self.built.shapes[shape as usize].geometry {
                        Geometry::Mesh(m) => m.uv_at(index as usize, b1, b2),
                        _ => [b1, b2],
                    };
                    Hit {
                        t,
                        p: ray.at(t),
                        n: (b - a).cross(c - a).normalize(),
                        uv,
                        shape,
                    }
                }
                Prim::Shape { shape } => self.shape_hit(shape, ray, tm)?,
            };
            best = Some(h);
            Some(h.t)
        });
        best
    }

    /// [`Scene::intersect`] for a ray that travels in `medium`: where the medium's shapes are
    /// all such a ray can meet first (they hold it, and nothing else comes near them), only
    /// they are tested, without the BVH; the hit is the same.
    #[inline]
    pub fn intersect_in(&self, medium: u32, ray: &Ray, t_max: f64) -> Option<Hit> {
        let Some(Some(own)) = self.built.enclosures.get(medium as usize) else {
            return self.intersect(ray, t_max);
        };
        let mut best: Option<Hit> = None;
        for &shape in own.iter() {
            let tm = best.map_or(t_max, |h| h.t);
            best = self.shape_hit(shape, ray, tm).or(best);
        }
        best
    }

    /// The hit of analytic shape `shape` (one primitive) closer than `t_max`, with its index.
    #[inline]
    fn shape_hit(&self, shape: u32, ray: &Ray, t_max: f64) -> Option<Hit> {
        let mut h = self.built.shapes[shape as usize].intersect_primitive(0, ray, t_max)?;
        h.shape = shape;
        Some(h)
    }

    /// A lower bound on the distance from `p` to every surface of the scene [mm]: a ray from
    /// `p` shorter than it meets nothing, so a random walk need not intersect the scene for
    /// such a flight (Geant4's "safety"). A few analytic shapes ([`CLEARANCE_SHAPES`]) are
    /// asked in turn; a scene with meshes looks its grid up ([`clearance_grid`]); 0 where
    /// neither applies (more analytic shapes, where a scan would cost more than the BVH).
    /// Shrunk by a margin far above the intersection routines' rounding.
    #[inline]
    pub fn clearance(&self, p: Vec3) -> f64 {
        let built = &*self.built;
        if built.clearance {
            clearance_of(&built.shapes, p, 0..built.shapes.len() as u32)
        } else if let Some(grid) = &built.grid {
            shrink(grid.clearance(p))
        } else {
            0.0
        }
    }

    /// [`Scene::clearance`] for a point in `medium`: where the medium's shapes hold it alone
    /// ([`Scene::intersect_in`]), the nearest surface is one of theirs (every other one lies
    /// outside their boxes, beyond their surface), so only they are asked, whatever the
    /// scene's size.
    #[inline]
    pub fn clearance_in(&self, medium: u32, p: Vec3) -> f64 {
        match self.built.enclosures.get(medium as usize) {
            Some(Some(own)) => clearance_of(&self.built.shapes, p, own.iter().copied()),
            _ => self.clearance(p),
        }
    }

    /// The first surface from `o` (in `medium`) along unit `d` within `t_max` [mm]: (hit
    /// point, normal), the face finder of a kernel clip
    /// ([`KernelClip`](crate::photon_map::KernelClip)).
    #[inline]
    pub fn first_face(&self, medium: u32, o: Vec3, d: Vec3, t_max: f64) -> Option<(Vec3, Vec3)> {
        // a grid lookup costs less than the BVH, and a kernel's rays are short
        if self.built.grid.is_some() && t_max < self.clearance(o) {
            return None;
        }
        self.intersect_in(medium, &Ray::new(o, d), t_max)
            .map(|h| (h.p, h.n))
    }

    /// Whether any surface lies on the ray with t in (0, t_max).
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f64) -> bool {
        self.built.bvh.any(ray, t_max, |slot, tm| {
            match self.built.prims[slot as usize] {
                Prim::Triangle {
                    corners: [a, b, c], ..
                } => intersect_corners(a, b, c, ray.o, ray.d, tm).is_some(),
                Prim::Shape { shape } => self.built.shapes[shape as usize]
                    .intersect_primitive(0, ray, tm)
                    .is_some(),
            }
        })
    }

    /// Boundary of shape `shape`.
    #[inline]
    pub fn boundary(&self, shape: u32) -> Boundary {
        self.built.shapes[shape as usize].boundary
    }

    /// World bounds of all shapes [mm] (lower, upper corner).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let b = self.built.bvh.bounds();
        (b.min, b.max)
    }

    /// Reflectance ρ of an opaque hit (0 for a dielectric boundary).
    #[inline]
    pub fn reflectance(&self, hit: &Hit) -> f64 {
        let s = &self.built.shapes[hit.shape as usize];
        match s.boundary {
            Boundary::Opaque { surface } => {
                self.surfaces[surface as usize].reflectance(hit, s.uv_scale)
            }
            Boundary::Dielectric { .. } => 0.0,
        }
    }

    /// Pick a light with probability proportional to its power: (index, probability).
    #[inline]
    pub fn pick_light(&self, u: f64) -> (usize, f64) {
        let i = self
            .light_cdf
            .partition_point(|&c| c <= u)
            .min(self.lights.len() - 1);
        let lo = if i == 0 { 0.0 } else { self.light_cdf[i - 1] };
        (i, self.light_cdf[i] - lo)
    }

    /// The probability with which [`Scene::pick_light`] picks light `i`.
    #[inline]
    pub fn light_probability(&self, i: usize) -> f64 {
        let lo = if i == 0 { 0.0 } else { self.light_cdf[i - 1] };
        self.light_cdf[i] - lo
    }

    /// Total power Φ of all lights.
    pub fn total_power(&self) -> f64 {
        self.lights.iter().map(|l| l.power()).sum()
    }

    /// Nearest area light a ray sees before `t_max`: (radiance, distance).
    #[inline]
    pub fn emitted(&self, ray: &Ray, t_max: f64) -> Option<(f64, f64)> {
        let mut best: Option<(f64, f64)> = None;
        for l in &self.lights {
            if let Some((le, t)) = l.le(ray, best.map_or(t_max, |b| b.1)) {
                best = Some((le, t));
            }
        }
        best
    }

    /// Number of primitives in the BVH.
    pub fn primitive_count(&self) -> usize {
        self.built.prims.len()
    }
}

/// Validate one band's media, surfaces and lights against the shapes; returns the lights'
/// power CDF.
fn check_band(
    media: &[Medium],
    surfaces: &[Surface],
    shapes: &[ShapeInstance],
    lights: &[Light],
    ambient_medium: u32,
) -> Result<Vec<f64>> {
    if media.is_empty() {
        return Err(Error::InvalidInput(
            "media is empty: at least the ambient medium (air) is needed".into(),
        ));
    }
    if ambient_medium as usize >= media.len() {
        return Err(Error::InvalidInput(format!(
            "ambient_medium = {ambient_medium} is out of range: allowed [0, {}]",
            media.len() - 1
        )));
    }
    for (i, s) in surfaces.iter().enumerate() {
        s.validate(&format!("surfaces[{i}]"))?;
    }
    for (i, s) in shapes.iter().enumerate() {
        match s.boundary {
            Boundary::Opaque { surface } => {
                if surface as usize >= surfaces.len() {
                    return Err(Error::InvalidInput(format!(
                            "shapes[{i}].boundary.surface = {surface} is out of range: {} surfaces defined",
                            surfaces.len()
                        )));
                }
            }
            Boundary::Dielectric { inside, outside } => {
                for (k, m) in [("inside", inside), ("outside", outside)] {
                    if m as usize >= media.len() {
                        return Err(Error::InvalidInput(format!(
                            "shapes[{i}].boundary.{k} = {m} is out of range: {} media defined",
                            media.len()
                        )));
                    }
                }
            }
        }
    }
    if lights.is_empty() {
        return Err(Error::InvalidInput(
            "lights is empty: a scene needs at least one light".into(),
        ));
    }
    for (i, l) in lights.iter().enumerate() {
        l.validate(&format!("lights[{i}]"))?;
    }
    let total: f64 = lights.iter().map(|l| l.power()).sum();
    if !(total > 0.0 && total.is_finite()) {
        return Err(Error::InvalidInput(format!(
                "lights: total power is {total}; at least one light must emit (radiance or intensity > 0)"
            )));
    }
    let mut acc = 0.0;
    let light_cdf: Vec<f64> = lights
        .iter()
        .map(|l| {
            acc += l.power() / total;
            acc
        })
        .collect();
    Ok(light_cdf)
}

/// The ray offset [`Scene::eps`] for a scene with this BVH, camera and lights.
fn ray_offset(bvh: &Bvh, camera: &Camera, lights: &[Light]) -> f64 {
    let b = bvh.bounds();
    let extent = if b.is_empty() {
        0.0
    } else {
        b.min.abs().max(b.max.abs()).max_element()
    };
    let extent = lights
        .iter()
        .fold(extent.max(camera.position.abs().max_element()), |e, l| {
            e.max(light_anchor(l).abs().max_element())
        });
    1e-7 * (extent + 1.0)
}

/// A point of a light (for the scene extent).
fn light_anchor(l: &Light) -> Vec3 {
    match *l {
        Light::Quad { corner, .. } => corner,
        Light::Disc { center, .. } => center,
        Light::Point { position, .. } | Light::Spot { position, .. } => position,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::phase::PhaseFunction;

    fn air() -> Medium {
        Medium::new("", 0.0, 0.0, 1.0, PhaseFunction::Isotropic).unwrap()
    }
    fn camera() -> Camera {
        Camera::new(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO, Vec3::Y, 40.0, 8, 8).unwrap()
    }
    fn point() -> Light {
        Light::Point {
            position: Vec3::new(0.0, 5.0, 5.0),
            intensity: 1.0,
        }
    }
    fn opaque() -> Boundary {
        Boundary::Opaque { surface: 0 }
    }
    fn lamb() -> Vec<Surface> {
        vec![Surface::Lambertian { reflectance: 0.5 }]
    }

    #[test]
    fn transformed_sphere_hit_and_normal() {
        let t = Transform::from_rows(
            "t",
            [
                [2.0, 0.0, 0.0, 1.0],
                [0.0, 1.0, 0.0, 0.0],
                [0.0, 0.0, 1.0, 0.0],
                [0.0, 0.0, 0.0, 1.0],
            ],
        )
        .unwrap();
        let s = ShapeInstance::new(
            "shapes[0]",
            Geometry::Sphere(Sphere {
                center: Vec3::ZERO,
                radius: 1.0,
            }),
            Some(t),
            opaque(),
        )
        .unwrap();
        let scene = Scene::new(camera(), vec![air()], lamb(), vec![s], vec![point()], 0).unwrap();
        // ellipsoid with semi-axis 2 along x, centred at x = 1
        let h = scene
            .intersect(&Ray::new(Vec3::new(10.0, 0.0, 0.0), -Vec3::X), 100.0)
            .unwrap();
        assert!((h.t - 7.0).abs() < 1e-12 && (h.n - Vec3::X).length() < 1e-12);
        let (lo, hi) = scene.bounds();
        assert!((lo - Vec3::new(-1.0, -1.0, -1.0)).length() < 1e-12);
        assert!((hi - Vec3::new(3.0, 1.0, 1.0)).length() < 1e-12);
        assert!(scene.occluded(&Ray::new(Vec3::new(10.0, 0.0, 0.0), -Vec3::X), 7.5));
        assert!(!scene.occluded(&Ray::new(Vec3::new(10.0, 0.0, 0.0), -Vec3::X), 6.5));
    }

    #[test]
    fn intersect_in_a_walled_off_medium_equals_the_bvh() {
        use crate::rng::Stream;
        let shape = |g: Geometry, b: Boundary| ShapeInstance::new("s", g, None, b).unwrap();
        let disc = |x: f64, z: f64| {
            Geometry::Cylinder(Cylinder {
                center: Vec3::new(x, 0.0, z),
                axis: Vec3::Z,
                radius: 5.0,
                height: 5.0,
            })
        };
        let inside = |m: u32| Boundary::Dielectric {
            inside: m,
            outside: 0,
        };
        let shapes = vec![
            shape(
                Geometry::Quad(Quad {
                    corner: Vec3::new(-100.0, -100.0, -0.1),
                    u: Vec3::new(200.0, 0.0, 0.0),
                    v: Vec3::new(0.0, 200.0, 0.0),
                }),
                opaque(),
            ),
            shape(disc(-8.0, 0.01), inside(1)),
            shape(disc(8.0, 5.0), inside(1)),
            // a ball resting on the table: its box touches the table's
            shape(
                Geometry::Sphere(Sphere {
                    center: Vec3::new(0.0, 20.0, 0.9),
                    radius: 1.0,
                }),
                inside(2),
            ),
        ];
        let glass = Medium::new("", 0.1, 1.0, 1.5, PhaseFunction::Isotropic).unwrap();
        let media = vec![air(), glass, glass];
        let cam = Camera::new(Vec3::new(0.0, -40.0, 35.0), Vec3::ZERO, Vec3::Z, 30.0, 8, 8);
        let scene = Scene::new(cam.unwrap(), media, lamb(), shapes, vec![point()], 0).unwrap();
        let own = |m: usize| scene.built.enclosures.get(m).cloned().flatten();
        assert_eq!(own(0), None, "the ambient medium");
        assert_eq!(
            own(1).as_deref(),
            Some(&[1u32, 2][..]),
            "two discs clear of all else"
        );
        assert_eq!(own(2), None, "a ball whose box touches the table");
        // rays from inside either disc, near its faces and rim too: the same hit, bit for bit
        let mut rng = Stream::new(11, 0, 0);
        for i in 0..20_000 {
            let [u, v] = rng.uniform2();
            let (rho, phi) = (5.0 * u.sqrt() * (1.0 - 1e-9), std::f64::consts::TAU * v);
            let (x0, z0) = if i % 2 == 0 { (-8.0, 0.01) } else { (8.0, 5.0) };
            let o = Vec3::new(
                x0 + rho * phi.cos(),
                rho * phi.sin(),
                z0 + 5.0 * rng.uniform(),
            );
            let d = crate::sampling::uniform_sphere(rng.uniform2());
            let t_max = if i % 3 == 0 {
                f64::INFINITY
            } else {
                3.0 * rng.uniform()
            };
            let ray = Ray::new(o, d);
            let (a, b) = (
                scene.intersect(&ray, t_max),
                scene.intersect_in(1, &ray, t_max),
            );
            let key = |h: Option<Hit>| h.map(|h| (h.t.to_bits(), h.shape, h.p, h.n));
            assert_eq!(key(a), key(b), "ray {i} from {o} along {d}");
            // the discs' own clearance bounds every surface, and no less than the scan's
            let c = scene.clearance_in(1, o);
            assert!(c >= scene.clearance(o) && c > 0.0, "clearance at {o}");
            assert!(
                scene.intersect(&ray, c).is_none(),
                "a surface within {c} of {o}"
            );
        }
    }

    #[test]
    fn rejects_bad_scenes_naming_the_shape() {
        let sphere = |r: f64, b: Boundary| {
            ShapeInstance::new(
                "shapes[2]",
                Geometry::Sphere(Sphere {
                    center: Vec3::ZERO,
                    radius: r,
                }),
                None,
                b,
            )
        };
        assert!(sphere(-1.0, opaque())
            .unwrap_err()
            .to_string()
            .contains("shapes[2].radius"));
        let mut open = TriangleMesh::uv_sphere(Vec3::ZERO, 1.0, 8, 8);
        open.triangles.pop();
        let e = ShapeInstance::new(
            "shapes[1]",
            Geometry::Mesh(open),
            None,
            Boundary::Dielectric {
                inside: 0,
                outside: 0,
            },
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("shapes[1]") && e.contains("closed"), "{e}");
        let mut bad = TriangleMesh::uv_sphere(Vec3::ZERO, 1.0, 8, 8);
        bad.triangles[5].swap(1, 2);
        let e = ShapeInstance::new(
            "shapes[3]",
            Geometry::Mesh(bad),
            None,
            Boundary::Dielectric {
                inside: 0,
                outside: 0,
            },
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("shapes[3]") && e.contains("oriented"), "{e}");
        let ok = sphere(20.0, opaque()).unwrap();
        let e = Scene::new(
            camera(),
            vec![air()],
            lamb(),
            vec![ok.clone()],
            vec![point()],
            0,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("camera.position") && e.contains("shapes[0]"),
            "{e}"
        );
        let e = Scene::new(camera(), vec![air()], lamb(), vec![], vec![], 0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("lights"), "{e}");
        // an inward-wound closed mesh is flipped to outward normals
        let mut inward = TriangleMesh::uv_sphere(Vec3::ZERO, 1.0, 16, 16);
        inward.flip();
        let s = ShapeInstance::new(
            "m",
            Geometry::Mesh(inward),
            None,
            Boundary::Dielectric {
                inside: 0,
                outside: 0,
            },
        )
        .unwrap();
        let scene = Scene::new(camera(), vec![air()], lamb(), vec![s], vec![point()], 0).unwrap();
        let h = scene
            .intersect(&Ray::new(Vec3::new(0.05, 0.02, 5.0), -Vec3::Z), 100.0)
            .unwrap();
        assert!(h.n.z > 0.9);
    }
}
