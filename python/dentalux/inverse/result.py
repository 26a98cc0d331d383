"""The result of one inversion."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

JSON_KEYS = ("mua", "mus", "musp", "albedo", "model", "fit_tt", "fit_tr", "residual",
             "mua_ci", "mus_ci", "seconds")


@dataclass
class FitResult:
    """Fitted coefficients of one sample and how well the forward model reproduces it.

    mua, mus, musp = mus (1 - g) [1/mm]; albedo = mus / (mua + mus); optical_thickness =
    (mua + mus) d; fit_tt, fit_tr: the model at the solution; residual = max(|fit_tt - tt|,
    |fit_tr - tr|). mua_ci, mus_ci [1/mm]: the range of coefficients that reproduce TT and TR
    within +-tt_err, +-tr_err (first-order propagation, see docs/inversion.md). When the lower
    end of mua_ci reaches 0, mua is not resolved by the data: ``mua_resolved`` is False and
    ``mua_upper_bound`` (= mua_ci[1]) is the meaningful number, not ``mua``.
    """

    mua: float
    mus: float
    musp: float
    albedo: float
    optical_thickness: float
    model: str
    fit_tt: float
    fit_tr: float
    residual: float
    mua_ci: list[float]
    mus_ci: list[float]
    seconds: float
    tt: float
    tr: float
    g: float
    n: float
    n_outside: float
    fd: float
    thickness: float
    tt_err: float
    tr_err: float
    mua_resolved: bool
    mua_upper_bound: float
    iterations: int
    evaluations: int
    converged: bool
    wavelength_nm: float | None = None
    mc_stderr: list[float] | None = None
    notes: list[str] = field(default_factory=list)

    def to_dict(self) -> dict:
        """Every field as a plain dict."""
        return asdict(self)

    def to_json(self) -> dict:
        """The CLI's JSON contract: exactly the keys of :data:`JSON_KEYS`."""
        d = self.to_dict()
        return {k: d[k] for k in JSON_KEYS}
