//! Photon maps: compact photon records, a balanced kd-tree over them, k-nearest and
//! fixed-radius queries, and the radiance estimates of the paper (eq. 11's multiple-scattering
//! term for volumes, the classic Σ f ΔΦ / (π r²) for surfaces).
//!
//! - [`tree`]: the photon record ([`Photon`]) and the map ([`PhotonMap`]): a balanced kd-tree
//!   with k-nearest ([`PhotonMap::knn`]) and fixed-radius ([`PhotonMap::for_each_within`])
//!   queries.
//! - [`kernel`]: the geometry of kernels near boundaries: the planes that orient and cut the
//!   layer kernel ([`Planes`]) and the rays that find other faces within it ([`KernelClip`]).
//! - [`estimators`]: the density estimates, named kernel then radius rule:
//!   [`PhotonMap::volume_sphere_knn`], [`PhotonMap::volume_layer_knn`],
//!   [`PhotonMap::volume_sphere_at_radius`], [`PhotonMap::volume_layer_at_radius`] (eq. 11's
//!   multiple-scattering term) and [`PhotonMap::irradiance_disc_knn`],
//!   [`PhotonMap::irradiance_clipped_disc_knn`], [`PhotonMap::irradiance_disc_at_radius`]
//!   (surface irradiance).
//!
//! Use: collect `Photon::new(position [mm], travel_direction, power)` records (the travel
//! direction is the direction the photon was moving when it landed, i.e. `-wi`), build with
//! [`PhotonMap::build`], then per shading point call an estimator (for a surface multiply the
//! irradiance by the BRDF, ρ/π for Lambertian). Photon power is the light's power Φ divided
//! by the number of photons emitted (not stored).
//!
//! Layout: a photon is 20 bytes ([`PHOTON_BYTES`]): position as 3 × f32, power as f32, and one
//! u32 holding the travel direction (octahedral map, 15 + 15 bits, error < 2e-4 rad) and the
//! kd-tree split axis (2 bits). The tree is implicit: the photons are permuted so that the
//! median of `[lo, hi)` sits at `(lo + hi) / 2` with the smaller half to its left, so the map
//! needs no memory beyond the photon array itself (100 M photons = 2.0 GB).
//!
//! Why not `kiddo`: its trees keep their own copy of the coordinates plus an item index per
//! point (≥ 16 bytes on top of the record), which breaks the memory target of 100 M photons in
//! < 3 GB; an implicit median tree is the classic photon-map structure (Jensen 2001) and is
//! short.

pub mod beam;
pub mod estimators;
pub mod kernel;
pub mod tree;

pub use beam::{BeamEstimate, BeamMap, Face, Segment};
pub use estimators::Estimate;
pub use kernel::{KernelClip, Planes};
pub use tree::{Neighbours, Photon, PhotonMap, PHOTON_BYTES};

#[cfg(test)]
mod beam_tests;
#[cfg(test)]
mod tests;
