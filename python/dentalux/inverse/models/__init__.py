"""Forward slab models behind one interface: (mua, mus) -> (TT, TR) for a given sample.

Every model is a class with ``name`` and ``forward(mua, mus, sample) -> (tt, tr)``; the
cheap analytic models accept numpy arrays of mua, mus [1/mm] and return arrays. TT is the
total transmittance (unscattered included) and TR the total reflectance, which includes the
first-surface specular reflection unless ``sample.diffuse_only`` (then that reflection, and
only that, is left out, as in MCML's Rd). All light is a collimated beam at normal incidence.

- ``mc``: the slab Monte Carlo simulator (exact transport, statistical error);
- ``ad``: adding-doubling (iadpython), exact transport to quadrature error;
- ``telegrapher``: steady-state telegrapher / P1 solution with Fresnel partial-current
  boundaries (the paper's model);
- ``km``: Kubelka-Munk two-flux with Saunderson's surface correction.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Sample:
    """What is known about the measured disc.

    g: HG anisotropy in (-1, 1); n: refractive index of the sample (>= 1); n_out: index of
    the surroundings (>= 1); thickness [mm]; fd: isotropic fraction of the phase function
    (paper eq. 10) in [0, 1]; diffuse_only: TR excludes the first-surface specular reflection.
    """

    g: float
    n: float
    thickness: float
    n_out: float = 1.0
    fd: float = 0.0
    diffuse_only: bool = False

    @property
    def g_eff(self) -> float:
        """Mean cosine of the eq. 10 phase function, (1 - fd) g: what the analytic models use."""
        return (1.0 - self.fd) * self.g


MODELS = ("mc", "ad", "telegrapher", "km")


def get_model(name: str, **options):
    """The forward model called ``name`` (one of :data:`MODELS`), built with ``options``."""
    if name == "telegrapher":
        from dentalux.inverse.models.telegrapher import Telegrapher

        return Telegrapher()
    if name == "km":
        from dentalux.inverse.models.km import KubelkaMunk

        return KubelkaMunk(k2=options.get("km_k2"))
    if name == "ad":
        from dentalux.inverse.models.ad import AddingDoubling

        return AddingDoubling(quad_pts=options.get("quad_pts"))
    if name == "mc":
        from dentalux.inverse.models.mc import MonteCarlo

        return MonteCarlo(
            photons=400_000 if options.get("photons") is None else options["photons"],
            seed=1 if options.get("seed") is None else options["seed"],
            estimator=options.get("estimator") or "weighted",
        )
    raise ValueError(f"model = {name!r}: allowed {', '.join(MODELS)}")
