"""``fit``: one (TT, TR) measurement -> (mua, mus) with an interval, for any forward model."""

from __future__ import annotations

import time

import numpy as np

from dentalux.inverse.bounds import check_measurement, check_number, clear_slab_tr
from dentalux.inverse.models import MODELS, Sample, get_model
from dentalux.inverse.models.boundary import specular
from dentalux.inverse.optimise import LOG_HI, LOG_LO, grid_start, jacobian, solve
from dentalux.inverse.result import FitResult

DEFAULT_TOL = {"mc": 1e-3, "ad": 1e-5, "telegrapher": 1e-7, "km": 1e-7}


def _vectorised(model, sample: Sample):
    """x (2,k) in ln units -> model values (2,k)."""

    def fun(x):
        x = np.asarray(x, float)
        tt, tr = model.forward(np.exp(x[0]), np.exp(x[1]), sample)
        return np.stack([np.asarray(tt, float), np.asarray(tr, float)])

    return fun


def _scalar(model, sample: Sample):
    def fun(x):
        tt, tr = model.forward(float(np.exp(x[0])), float(np.exp(x[1])), sample)
        return np.array([float(tt), float(tr)])

    return fun


def _stand_in(sample: Sample, quad_pts):
    """Cheap model with the same physics as mc: adding-doubling when installed and the
    surroundings are air (n_outside = 1), else the telegrapher model."""
    if sample.n_out != 1.0:
        return get_model("telegrapher")
    try:
        return get_model("ad", quad_pts=quad_pts)
    except ValueError:
        return get_model("telegrapher")


def _multistart(model, sample: Sample, target: np.ndarray, tol: float):
    """Solve a vectorised model from the best grid points until one converges."""
    vec, scal = _vectorised(model, sample), _scalar(model, sample)
    best = None
    for x0 in grid_start(vec, target, k=6):
        sol = solve(scal, target, x0, tol, jac_fun=vec)
        if best is None or sol.residual < best.residual:
            best = sol
        if sol.converged:
            break
    return best


def _start(fwd, sample: Sample, target: np.ndarray, quad_pts) -> np.ndarray:
    """Starting point: grid search (analytic models); the telegrapher / ad solution otherwise."""
    model_name = fwd.name
    if model_name in ("telegrapher", "km"):
        return grid_start(_vectorised(fwd, sample), target)
    x = _multistart(get_model("telegrapher"), sample, target, 1e-7).x
    if model_name == "mc":
        sub = _stand_in(sample, quad_pts)
        if sub.name == "ad":
            x = solve(_scalar(sub, sample), target, x, 1e-5, jac_fun=_vectorised(sub, sample)).x
    return x


def fit(tt: float, tr: float, n: float, g: float, thickness: float, model: str = "mc",
        fd: float = 0.0, n_outside: float = 1.0, tr_diffuse_only: bool = False,
        tt_err: float = 0.005, tr_err: float = 0.005, tol: float | None = None,
        photons: int | None = None, seed: int | None = None, estimator: str | None = None,
        quad_pts: int | None = None, km_k2: float | None = None,
        wavelength_nm: float | None = None) -> FitResult:
    """Find mua, mus [1/mm] of a slab from its total transmittance and reflectance.

    tt, tr: fractions for a normal collimated beam (tr includes the front-face specular
    reflection unless ``tr_diffuse_only``); n, n_outside: refractive indices; g: HG
    anisotropy; thickness [mm]; fd: isotropic fraction (eq. 10). tt_err, tr_err: absolute
    measurement uncertainty (the interval holds every (mua, mus) that reproduces the data
    within these). tol: fit tolerance on TT/TR (default 1e-3 for mc, tighter for the others).
    photons, seed, estimator: for ``mc`` (defaults 400000, 1, "weighted"); quad_pts for
    ``ad``; km_k2: an empirical Saunderson k2 for ``km`` (default: the Fresnel value).
    Raises ValueError for bad input or data outside what the model can produce.
    """
    start = time.perf_counter()
    if model not in MODELS:
        raise ValueError(f"model = {model!r}: allowed {', '.join(MODELS)}")
    tt = check_number("tt", tt, 0.0, 1.0, lo_open=True, hi_open=True)
    tr = check_number("tr", tr, 0.0, 1.0, hi_open=True)
    n = check_number("n", n, 1.0, 10.0)
    n_outside = check_number("n_outside", n_outside, 1.0, 10.0)
    g = check_number("g", g, -1.0, 1.0, lo_open=True, hi_open=True)
    thickness = check_number("thickness", thickness, 0.0, 1e4, lo_open=True, unit="mm")
    fd = check_number("fd", fd, 0.0, 1.0)
    tt_err = check_number("tt_err", tt_err, 0.0, 0.5, lo_open=True)
    tr_err = check_number("tr_err", tr_err, 0.0, 0.5, lo_open=True)
    if tol is None:
        tol = DEFAULT_TOL[model]
    tol = check_number("tol", tol, 0.0, 0.1, lo_open=True)
    if wavelength_nm is not None:  # recorded in the result and the spectrum TOML
        from dentalux.inputs import WAVELENGTH_RANGE_NM

        wavelength_nm = check_number("wavelength_nm", wavelength_nm, *WAVELENGTH_RANGE_NM,
                                     unit="nm")
    check_measurement(tt, tr, n, n_outside, tr_diffuse_only)
    if model == "ad" and n_outside != 1.0:
        raise ValueError(
            f"n_outside = {n_outside}: model 'ad' allows only 1 (iadpython reads n_outside as "
            "glass slides with air beyond, not as a surrounding medium); use mc or telegrapher"
        )

    sample = Sample(g=g, n=n, thickness=thickness, n_out=n_outside, fd=fd,
                    diffuse_only=bool(tr_diffuse_only))
    fwd = get_model(model, photons=photons, seed=seed, estimator=estimator, quad_pts=quad_pts,
                    km_k2=km_k2)
    target = np.array([tt, tr])
    x0 = None if model in ("telegrapher", "km") else _start(fwd, sample, target, quad_pts)

    if model == "mc":
        jac_model = _stand_in(sample, quad_pts)
        sol = solve(_scalar(fwd, sample), target, x0, tol,
                    jac_fun=_vectorised(jac_model, sample), max_iter=8)
        # Standard errors of the last run (at or next to the solution; they vary slowly).
        stderr = list(fwd.last_stderr)
    elif model in ("telegrapher", "km"):
        jac_model = fwd
        sol = _multistart(fwd, sample, target, tol)
        stderr = None
    else:
        jac_model = fwd
        sol = solve(_scalar(fwd, sample), target, x0, tol, jac_fun=_vectorised(fwd, sample))
        stderr = None

    mua, mus = (float(v) for v in np.exp(sol.x))
    notes: list[str] = []
    limit = 5.0 * tol if model == "mc" else max(10.0 * tol, 1e-4)
    if sol.residual > limit:
        at_edge = np.isclose(sol.x, LOG_LO, atol=1e-6)
        where = " (mua reached its lower limit)" if at_edge[0] else ""
        tr_clear = clear_slab_tr(tt, n, n_outside, bool(tr_diffuse_only))
        if tr < tr_clear:
            where += (f"; tr is below {tr_clear:.5f}, the TR of a non-scattering slab with "
                      "this TT (bound crossed: TR >= TR_clear(TT))")
        raise ValueError(
            f"model {model!r} cannot reproduce tt = {tt}, tr = {tr} for n = {n}, g = {g}, "
            f"thickness = {thickness} mm: closest fit tt = {sol.values[0]:.5f}, "
            f"tr = {sol.values[1]:.5f}{where}"
        )
    if not sol.converged:
        notes.append(f"residual {sol.residual:.2e} above tol {tol:.1e}")

    # Interval: the +-err box of (TT, TR) mapped onto (mua, mus), both to first order and
    # through its four corners (each solved with the cheap model, as a shift from that
    # model's own solution), taking the hull; for mc its statistical error (2 standard
    # errors) widens the box.
    err = np.array([tt_err, tr_err])
    if stderr is not None:
        err = err + 2.0 * np.asarray(stderr)
    lo, hi = _interval(jac_model, sample, target, err, sol.x, np.array([mua, mus]))
    mua_lo, mua_hi = float(lo[0]), float(hi[0])
    mus_lo, mus_hi = float(lo[1]), float(hi[1])
    resolved = mua_lo > 2.0 * float(np.exp(LOG_LO[0]))
    if not resolved:
        mua_lo = 0.0
        notes.append(f"mua not resolved: upper bound {mua_hi:.4g} 1/mm")
    if tt - err[0] <= 0.0:
        notes.append("tt is within its uncertainty of 0: the upper ends of the intervals "
                     "are set by the search limits, not by the data")

    return FitResult(
        mua=mua, mus=mus, musp=mus * (1.0 - g), albedo=mus / (mua + mus),
        optical_thickness=(mua + mus) * thickness, model=model,
        fit_tt=float(sol.values[0]), fit_tr=float(sol.values[1]), residual=sol.residual,
        mua_ci=[float(mua_lo), float(mua_hi)], mus_ci=[float(mus_lo), float(mus_hi)],
        seconds=time.perf_counter() - start, tt=tt, tr=tr, g=g, n=n, n_outside=n_outside,
        fd=fd, thickness=thickness, tt_err=tt_err, tr_err=tr_err, mua_resolved=bool(resolved),
        mua_upper_bound=float(mua_hi), iterations=sol.iterations, evaluations=sol.evaluations,
        converged=sol.converged, wavelength_nm=wavelength_nm,
        mc_stderr=[float(s) for s in stderr] if stderr is not None else None, notes=notes,
    )


def _interval(model, sample: Sample, target: np.ndarray, err: np.ndarray, x_fit: np.ndarray,
              mu_fit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper) of (mua, mus) over the box target +- err, by ``model`` (a cheap one).

    First order: half-widths |J^-1| err at the solution. Nonlinear: each corner of the box,
    moved into the region no slab can leave (0 < TT <= T_clear, TT + TR <= 1, TR >= R0), is
    solved from ``model``'s own solution at the target; the shift between the two is added to
    the fitted value. Corners the model cannot reach are left out.
    """
    vec = _vectorised(model, sample)
    scal = _scalar(model, sample)
    j_log = jacobian(vec, x_fit)
    j = j_log / mu_fit[None, :]
    try:
        half = np.abs(np.linalg.inv(j)) @ err
    except np.linalg.LinAlgError:
        half = np.full(2, np.inf)
    half = np.where(np.isfinite(half), half, 1e30)
    lo, hi = mu_fit - half, mu_fit + half

    centre = solve(scal, target, x_fit, 1e-7, jac_fun=vec, max_iter=30, j0=j_log)
    if centre.residual < 1e-4:
        jc = j_log  # x_fit is at or next to the centre: its slopes serve as chord slopes
        mu_c = np.exp(centre.x)
        r0 = specular(sample.n, sample.n_out)
        t_clear = (1.0 - r0) / (1.0 + r0)
        tr_min = 1e-9 if sample.diffuse_only else r0 + 1e-9
        for s_tt, s_tr in ((-1, -1), (-1, 1), (1, -1), (1, 1)):
            c_tt = float(np.clip(target[0] + s_tt * err[0], 1e-9, t_clear - 1e-9))
            c_tr = float(np.clip(target[1] + s_tr * err[1], tr_min, 1.0))
            c_tr = min(c_tr, 1.0 - 1e-9 - c_tt)
            try:
                dx = np.linalg.solve(jc, np.array([c_tt, c_tr]) - centre.values)
            except np.linalg.LinAlgError:
                dx = np.zeros(2)
            x_start = centre.x + np.clip(dx, -3.0, 3.0)
            sol = solve(scal, np.array([c_tt, c_tr]), x_start, 1e-6, jac_fun=vec,
                        max_iter=40, j0=jc)
            if sol.residual > 1e-4:
                continue
            mu = mu_fit + (np.exp(sol.x) - mu_c)
            lo, hi = np.minimum(lo, mu), np.maximum(hi, mu)
    if target[0] - err[0] <= 0.0:
        # TT is indistinguishable from 0: only TR constrains, which fixes a ratio of the
        # coefficients but not their scale, so nothing bounds them from above.
        hi = np.maximum(hi, np.exp(LOG_HI))
    return np.maximum(lo, 0.0), hi
