//! The energy ledger of a photon pass: where the emitted power went (the closed-form checks
//! of tests/volume_transport.rs and tests/spectral_photons.rs read it).

/// Where the emitted power went (sums of photon powers, same units as light power Φ).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Ledger {
    /// Power emitted by the lights (Σ over photons).
    pub emitted: f64,
    /// Power absorbed inside each medium (albedo roulette), indexed like `scene.media`.
    pub absorbed_medium: Vec<f64>,
    /// Power absorbed by opaque surfaces.
    pub absorbed_surface: f64,
    /// Power that left the scene.
    pub escaped: f64,
    /// Power of photons dropped by the event guard.
    pub cut: f64,
    /// Power stored in each volume map (counted once per stored event).
    pub stored_volume: Vec<f64>,
    /// Power stored in the surface map.
    pub stored_surface: f64,
}

impl Ledger {
    /// An empty ledger for `media` media.
    pub fn new(media: usize) -> Self {
        Self {
            absorbed_medium: vec![0.0; media],
            stored_volume: vec![0.0; media],
            ..Self::default()
        }
    }
    /// Multiply every entry by `f`.
    pub fn scale(&mut self, f: f64) {
        for v in [
            &mut self.emitted,
            &mut self.absorbed_surface,
            &mut self.escaped,
            &mut self.cut,
            &mut self.stored_surface,
        ] {
            *v *= f;
        }
        for v in self
            .absorbed_medium
            .iter_mut()
            .chain(&mut self.stored_volume)
        {
            *v *= f;
        }
    }
    /// Add `o`'s entries.
    pub fn add(&mut self, o: &Ledger) {
        self.emitted += o.emitted;
        self.absorbed_surface += o.absorbed_surface;
        self.escaped += o.escaped;
        self.cut += o.cut;
        self.stored_surface += o.stored_surface;
        for (a, b) in self.absorbed_medium.iter_mut().zip(&o.absorbed_medium) {
            *a += b;
        }
        for (a, b) in self.stored_volume.iter_mut().zip(&o.stored_volume) {
            *a += b;
        }
    }
}
