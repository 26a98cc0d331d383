//! The settings of the render contract (docs/render-contract.md) that every integrator reads,
//! their defaults and ranges, and the statistics returned with the image.

use crate::error::{Error, Result};
use crate::rng::PASS_BITS;

/// Bound on the pass number: passes run 1 ..= MAX_PASSES − 1 (the pass number must fit
/// [`PASS_BITS`] bits of the seeds and stream tags, `rng::pass_seed` and `rng::pass_tag`).
pub const MAX_PASSES: u32 = 1 << PASS_BITS;

/// Default of [`Settings::kernel_layer`] (`VpmParams::layer`): the layer kernel's
/// half-height over the gathering radius (0.2 and 0.5 measured the same on the slab;
/// docs/notes/2026-12-02-vpm-convergence.md).
pub const DEFAULT_LAYER: f64 = 0.3;

/// Default of [`Settings::kernel_clip`] (`VpmParams::clip`): on. On Fig. 3 it lowers the
/// bias of averaged passes from 3.9 % to 2.8 % (rms over the image) for about 25 % more
/// camera time (docs/notes/2026-12-02-vpm-convergence.md).
pub const DEFAULT_CLIP: bool = true;

/// Which integrator renders the band.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Integrator {
    /// Direct light + specular dielectrics + surface photon map (opaque scenes, clear media).
    Pm,
    /// Brute-force path tracer with next-event estimation: the reference for `pm`.
    Path,
    /// Volume photon mapping, single scattering by shadow rays (the paper).
    Vpm,
    /// Volume photon mapping, every scattering event in the map.
    VpmFull,
    /// Reference volumetric path tracer.
    Volpath,
    /// The same, with next-event estimation also through flat refracting faces (planar_nee.rs):
    /// same expectation, a faster reference where light enters media through flat faces.
    VolpathNee,
    /// Progressive photon mapping.
    Ppm,
    /// Volume photon mapping with the beam radiance estimate: `vpm` with
    /// `volume_estimator = "beam"` (photon_map/beam.rs).
    Bre,
}

impl Integrator {
    /// Every integrator with its contract name, in the order the docs list them.
    pub const ALL: [(Integrator, &'static str); 8] = [
        (Integrator::Pm, "pm"),
        (Integrator::Path, "path"),
        (Integrator::Vpm, "vpm"),
        (Integrator::VpmFull, "vpm-full"),
        (Integrator::Volpath, "volpath"),
        (Integrator::VolpathNee, "volpath-nee"),
        (Integrator::Ppm, "ppm"),
        (Integrator::Bre, "bre"),
    ];

    /// The contract's name (`"vpm-full"`).
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(i, _)| *i == self)
            .map_or("", |(_, n)| n)
    }

    /// Parse the contract's name (one of [`Self::ALL`]).
    pub fn parse(name: &str) -> Result<Self> {
        match Self::ALL.iter().find(|(_, n)| *n == name) {
            Some((i, _)) => Ok(*i),
            None => {
                let allowed: Vec<String> =
                    Self::ALL.iter().map(|(_, n)| format!("{n:?}")).collect();
                Err(Error::InvalidInput(format!(
                    "settings.integrator = {name:?}: allowed {}",
                    allowed.join(", ")
                )))
            }
        }
    }

    /// Whether it traces photons (all but the path tracers).
    pub fn traces_photons(self) -> bool {
        !matches!(
            self,
            Integrator::Path | Integrator::Volpath | Integrator::VolpathNee
        )
    }

    /// Whether it traces volume photons (`vpm`, `vpm-full`, `ppm`, `bre`): the integrators
    /// a `volume_estimator` applies to.
    pub fn traces_volume_photons(self) -> bool {
        matches!(
            self,
            Integrator::Vpm | Integrator::VpmFull | Integrator::Ppm | Integrator::Bre
        )
    }

    /// Whether a multi-band render may trace one spectral photon pass for all its bands
    /// (`settings.spectral_photons`) and one camera path for all of them
    /// (`settings.hero_camera`): the one-pass volume integrators.
    pub fn shares_bands(self) -> bool {
        matches!(
            self,
            Integrator::Vpm | Integrator::VpmFull | Integrator::Bre
        )
    }
}

/// How the camera pass estimates multiple scattering from a volume photon map.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VolumeEstimator {
    /// Eq. 11: a march along the ray with a density estimate at every point.
    Points,
    /// The beam radiance estimate: one query per ray segment (photon_map/beam.rs).
    Beam,
}

impl VolumeEstimator {
    /// Every estimator, in the order of [`Self::NAMES`].
    const ALL: [VolumeEstimator; 2] = [VolumeEstimator::Points, VolumeEstimator::Beam];
    /// The contract's names, in order.
    pub const NAMES: [&'static str; 2] = ["points", "beam"];

    /// The contract's name.
    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }

    /// Parse the contract's name (one of [`Self::NAMES`]).
    pub fn parse(name: &str) -> Result<Self> {
        match Self::NAMES.iter().position(|n| *n == name) {
            Some(i) => Ok(Self::ALL[i]),
            None => {
                let allowed: Vec<String> = Self::NAMES.iter().map(|n| format!("{n:?}")).collect();
                Err(Error::InvalidInput(format!(
                    "settings.volume_estimator = {name:?}: allowed {}",
                    allowed.join(", ")
                )))
            }
        }
    }
}

/// Default of [`Settings::aim`]: emit as the lights do. Aiming is opt-in because it changes
/// how many photons a given `volume_photons` stores (and so memory and time): on the 5 mm
/// Fig. 3 disc at aim 0.5, 21× more (2.7 M → 56 M from 5 M photons).
pub const DEFAULT_AIM: f64 = 0.0;

/// Render settings (see docs/render-contract.md; `None` = derive from the scene).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// The integrator.
    pub integrator: Integrator,
    /// Camera samples per pixel (≥ 1).
    pub spp: u32,
    /// Photons emitted for the surface photon map.
    pub photons: u64,
    /// Photons emitted for the volume photon maps (with `volume_stored`: at most this many).
    pub volume_photons: u64,
    /// Photons the volume maps of a pass should hold (0: no budget). Photons are emitted until
    /// the maps hold at least this many (the paper counts its
    /// 100 000 000 photons this way) or `volume_photons` have been emitted; powers are
    /// normalised by the number actually emitted.
    pub volume_stored: u64,
    /// Fraction of the volume pass's photons aimed at the scattering media's bounding
    /// spheres, in [0, 1) (`integrators::aim`; unbiased mixture). 0: emit as the lights do.
    pub aim: f64,
    /// Photons per density estimate.
    pub k: usize,
    /// Photons per estimate of the surface photon map ([`Settings::surface_photons_k`]).
    pub surface_k: Option<usize>,
    /// Largest gathering radius [mm]: of every photon map, unless `surface_radius` sets the
    /// surface map's.
    pub radius: Option<f64>,
    /// Largest gathering radius of the surface photon map [mm] ([`Settings::surface_cap`]).
    pub surface_radius: Option<f64>,
    /// March step [mm]: how finely a camera ray's segment in a medium is sampled
    /// (`vpm::march_points`).
    pub step: Option<f64>,
    /// Seed of every random stream.
    pub seed: u64,
    /// Band index (mixed into the streams only).
    pub band: u64,
    /// Longest path (bounces / boundary events).
    pub max_depth: u32,
    /// Progressive photon mapping passes.
    pub passes: u32,
    /// Progressive photon mapping radius reduction α in (0, 1).
    pub alpha: f64,
    /// First pass to render, 0-based: `ppm` renders passes `pass_index + 1 ..= pass_index +
    /// passes` of its schedule (one task per pass for distributed renders); other
    /// integrators draw from an independent seed stream per pass index (0 = the plain seed).
    pub pass_index: u32,
    /// `pm`: final gathering (one diffuse bounce before the density estimate).
    pub final_gather: bool,
    /// `vpm`, `vpm-full`, `ppm`: half-height of the boundary-aligned layer kernel over the
    /// gathering radius, in [0, 1]; 0 the sphere (see `VpmParams::layer`).
    pub kernel_layer: f64,
    /// `vpm`, `vpm-full`, `ppm`: clip the layer kernel (and vpm's surface disc) by every
    /// other face within it, not only the camera ray's entry and exit planes (see
    /// `VpmParams::clip`).
    pub kernel_clip: bool,
    /// `vpm`, `vpm-full`, `ppm`: the volume estimator (`bre` is `vpm` with the beam).
    pub volume_estimator: VolumeEstimator,
    /// `vpm`, `vpm-full`, `bre` over several bands: one spectral photon pass for all bands
    /// (hero-band walks, balance-heuristic powers: `integrators::hero`) instead of one
    /// pass per band, so every band's maps hold the same photons.
    pub spectral_photons: bool,
    /// `vpm`, `vpm-full`, `bre` over several bands: one camera path per pixel sample for
    /// all bands, with a throughput per band (hero-wavelength camera paths:
    /// `integrators::hero_camera`), instead of one camera pass per band. Every band's maps
    /// are then held at once.
    pub hero_camera: bool,
}

impl Settings {
    /// The surface photon map's largest gathering radius [mm]: `surface_radius`, else
    /// `radius`; `None` derives it from the map. A volume map's radius suits a medium's
    /// thickness (tenths of a millimetre in a disc), while a surface map holds a few photons
    /// per square millimetre over a whole floor: one radius for both leaves the surface
    /// estimate a handful of photons.
    pub fn surface_cap(&self) -> Option<f64> {
        self.surface_radius.or(self.radius)
    }

    /// Photons per estimate of the surface photon map: `surface_k`, else `k`. Behind a
    /// surface estimate in `vpm` the direct light is traced by shadow rays, so the map
    /// carries only the indirect part and its noise is small beside a volume estimate's
    /// (k photons each); fewer photons shrink its radius, and with it the bias where the
    /// disc reaches past a surface's edge, at a cheaper query (docs/notes/2026-12-06-bre.md).
    pub fn surface_photons_k(&self) -> usize {
        self.surface_k.unwrap_or(self.k)
    }

    /// The volume estimator in effect: `bre` always uses the beam.
    pub fn estimator(&self) -> VolumeEstimator {
        if self.integrator == Integrator::Bre {
            VolumeEstimator::Beam
        } else {
            self.volume_estimator
        }
    }
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            integrator: Integrator::Pm,
            spp: 16,
            photons: 200_000,
            volume_photons: 1_000_000,
            volume_stored: 0,
            aim: DEFAULT_AIM,
            k: 64,
            surface_k: None,
            radius: None,
            surface_radius: None,
            step: None,
            seed: 1,
            band: 0,
            max_depth: 64,
            passes: 1,
            alpha: 0.7,
            pass_index: 0,
            final_gather: false,
            kernel_layer: DEFAULT_LAYER,
            kernel_clip: DEFAULT_CLIP,
            volume_estimator: VolumeEstimator::Points,
            spectral_photons: false,
            hero_camera: false,
        }
    }
}

/// The values a setting may take (what [`Settings::validate`] and the Python schema check).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Range {
    /// An integer ≥ `lo`.
    Integer {
        /// Smallest allowed value.
        lo: u64,
    },
    /// A real number between `lo` and `hi`, each end open or closed.
    Real {
        /// Lower end.
        lo: f64,
        /// Whether `lo` itself is excluded.
        lo_open: bool,
        /// Upper end.
        hi: f64,
        /// Whether `hi` itself is excluded.
        hi_open: bool,
    },
    /// A length > 0 [mm], or absent (derived from the scene).
    Positive,
    /// true or false.
    Boolean,
    /// One of [`Integrator::ALL`]'s names.
    Integrator,
    /// One of these names.
    Choice(&'static [&'static str]),
}

/// One key of the settings: its name, its allowed values, and whether a scene's `[render]`
/// table may set it (the rest are per call: `pass_index`, `band`, `threads`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Key {
    /// The contract's key.
    pub name: &'static str,
    /// Allowed values.
    pub range: Range,
    /// Settable in a scene's `[render]` table.
    pub scene: bool,
}

const fn key(name: &'static str, range: Range, scene: bool) -> Key {
    Key { name, range, scene }
}
const fn at_least(lo: u64) -> Range {
    Range::Integer { lo }
}
/// Real numbers in [0, 1) (`aim`), (0, 1) (`alpha`), [0, 1] (`kernel_layer`).
const fn unit_interval(lo_open: bool, hi_open: bool) -> Range {
    Range::Real {
        lo: 0.0,
        lo_open,
        hi: 1.0,
        hi_open,
    }
}

/// Every key of the settings contract, in the order the docs and error messages list them.
/// Defaults are [`Settings::default`]'s; `threads` (worker threads, default all cores) is
/// read by the contract decoder, not stored in [`Settings`].
pub const KEYS: [Key; 24] = [
    key("integrator", Range::Integrator, true),
    key("spp", at_least(1), true),
    key("photons", at_least(0), true),
    key("volume_photons", at_least(0), true),
    key("volume_stored", at_least(0), true),
    key("aim", unit_interval(false, true), true),
    key("k", at_least(1), true),
    key("surface_k", at_least(1), true),
    key("radius", Range::Positive, true),
    key("surface_radius", Range::Positive, true),
    key("step", Range::Positive, true),
    key("seed", at_least(0), true),
    key("max_depth", at_least(1), true),
    key("passes", at_least(1), true),
    key("alpha", unit_interval(true, true), true),
    key("final_gather", Range::Boolean, true),
    key("kernel_layer", unit_interval(false, false), true),
    key("kernel_clip", Range::Boolean, true),
    key(
        "volume_estimator",
        Range::Choice(&VolumeEstimator::NAMES),
        true,
    ),
    key("spectral_photons", Range::Boolean, true),
    key("hero_camera", Range::Boolean, true),
    key("pass_index", at_least(0), false),
    key("band", at_least(0), false),
    key("threads", at_least(1), false),
];

/// The range of `name` in [`KEYS`].
fn range_of(name: &str) -> Range {
    KEYS.iter()
        .find(|k| k.name == name)
        .map_or(Range::Positive, |k| k.range)
}

impl Settings {
    /// Check ranges ([`KEYS`]); errors name `settings.<key>`. Input from Python was checked
    /// against the same table where it came in (scene/schema.py): this is the core's guard
    /// for every other caller.
    pub fn validate(&self) -> Result<()> {
        for (k, v) in [
            ("spp", self.spp as u64),
            ("k", self.k as u64),
            ("surface_k", self.surface_photons_k() as u64),
            ("max_depth", self.max_depth as u64),
            ("passes", self.passes as u64),
        ] {
            if let Range::Integer { lo } = range_of(k) {
                if v < lo {
                    return Err(Error::InvalidInput(format!(
                        "settings.{k} = {v} is out of range: allowed ≥ {lo}"
                    )));
                }
            }
        }
        // pass numbers live in PASS_BITS bits of the seeds (rng::pass_seed, tiles::film_key)
        let last = self.pass_index as u64 + self.passes as u64;
        if last >= MAX_PASSES as u64 {
            return Err(Error::InvalidInput(format!(
                "settings.pass_index + settings.passes = {last} is out of range: allowed [1, {}]",
                MAX_PASSES - 1
            )));
        }
        for (k, v) in [
            ("radius", self.radius),
            ("surface_radius", self.surface_radius),
            ("step", self.step),
        ] {
            if let Some(v) = v {
                crate::error::check_positive(&format!("settings.{k}"), v, "mm")?;
            }
        }
        for (k, v) in [
            ("alpha", self.alpha),
            ("aim", self.aim),
            ("kernel_layer", self.kernel_layer),
        ] {
            if let Range::Real {
                lo,
                lo_open,
                hi,
                hi_open,
            } = range_of(k)
            {
                let field = format!("settings.{k}");
                crate::error::check_range(&field, v, lo, lo_open, hi, hi_open, "")?;
            }
        }
        if self.volume_estimator == VolumeEstimator::Beam
            && !self.integrator.traces_volume_photons()
        {
            let volume: Vec<&str> = (Integrator::ALL.iter())
                .filter(|(i, _)| i.traces_volume_photons())
                .map(|(_, n)| *n)
                .collect();
            return Err(Error::InvalidInput(format!(
                "settings.volume_estimator = \"beam\" applies to the volume photon integrators \
                 ({}), not to settings.integrator = {:?}",
                volume.join(", "),
                self.integrator.name()
            )));
        }
        for (on, name) in [
            (self.spectral_photons, "spectral_photons"),
            (self.hero_camera, "hero_camera"),
        ] {
            if on && !self.integrator.shares_bands() {
                let allowed: Vec<&str> = (Integrator::ALL.iter())
                    .filter(|(i, _)| i.shares_bands())
                    .map(|(_, n)| *n)
                    .collect();
                return Err(Error::InvalidInput(format!(
                    "settings.{name} = true applies to {}, not to settings.integrator = {:?}",
                    allowed.join(", "),
                    self.integrator.name()
                )));
            }
        }
        Ok(())
    }

    /// Photons one pass of one band traces: the unit of the progress count besides pixels
    /// (`control.done()` reaches this + width × height). None for the path tracers, the
    /// surface photons for `pm`, and for the volume integrators also the volume photons
    /// (those stored when `volume_stored` sets a budget: emission then stops at the budget).
    pub fn photons_traced(&self) -> u64 {
        if !self.integrator.traces_photons() {
            return 0;
        }
        let volume = if self.volume_stored > 0 {
            self.volume_stored
        } else {
            self.volume_photons
        };
        self.photons
            + if self.integrator.traces_volume_photons() {
                volume
            } else {
                0
            }
    }
}

/// What a render measured besides the image.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Stats {
    /// Integrator name as in the contract.
    pub integrator: String,
    /// Wall-clock seconds of the whole band.
    pub seconds_total: f64,
    /// Seconds tracing photons.
    pub seconds_photons: f64,
    /// Seconds building photon-map kd-trees.
    pub seconds_build: f64,
    /// Seconds of the camera pass.
    pub seconds_camera: f64,
    /// Photons emitted.
    pub photons_emitted: u64,
    /// Photons stored (all maps).
    pub photons_stored: u64,
    /// Bytes per stored photon.
    pub bytes_per_photon: u64,
    /// Memory of all photon maps [bytes].
    pub photon_map_bytes: u64,
    /// Surface gathering radius in use [mm] (0 when none).
    pub radius: f64,
    /// Rays traced by the camera pass (intersection and shadow queries).
    pub rays: u64,
    /// Camera samples per pixel.
    pub spp: u32,
    /// Volume estimator (`points`, `beam`; empty for integrators without volume photons).
    pub estimator: String,
    /// Integrator-specific figures (name, value).
    pub extra: Vec<(String, f64)>,
}
