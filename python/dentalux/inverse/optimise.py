"""Solve forward(mua, mus) = (TT, TR) for (mua, mus): a damped Newton iteration in log space.

Unknowns are x = (ln mua, ln mus), which keeps both positive and makes the steps scale-free.
The Jacobian comes from central finite differences of a *Jacobian model*: the model itself
when it is cheap, or a cheap stand-in with the same physics (adding-doubling, else the
telegrapher model) for the Monte Carlo model. With a stand-in the iteration is a defect
correction, x <- x - J_standin^-1 (f_mc(x) - target): it converges to the point where the
Monte Carlo model (common random numbers) matches the target, at a rate set by how well the
stand-in's slopes match (typically one or two Monte Carlo runs from a good start).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

LOG_LO = np.log(np.array([1e-7, 1e-6]))  # lower limits of (mua, mus) [1/mm]
LOG_HI = np.log(np.array([1e4, 1e5]))  # upper limits of (mua, mus) [1/mm]
MAX_STEP = 3.0  # largest step in ln units (a factor of 20)


@dataclass
class Solution:
    """Where the iteration stopped: x = (ln mua, ln mus), model values, counts."""

    x: np.ndarray
    values: np.ndarray
    residual: float
    iterations: int
    evaluations: int
    converged: bool


def jacobian(fun: Callable, x: np.ndarray, h: float = 1e-4) -> np.ndarray:
    """d(TT, TR)/d(ln mua, ln mus) by central differences; ``fun`` maps (2,k) arrays."""
    pts = np.stack([x + [h, 0], x - [h, 0], x + [0, h], x - [0, h]], axis=1)
    v = np.asarray(fun(pts))  # shape (2, 4)
    return np.stack([(v[:, 0] - v[:, 1]) / (2 * h), (v[:, 2] - v[:, 3]) / (2 * h)], axis=1)


def grid_start(fun: Callable, target: np.ndarray, k: int = 1) -> np.ndarray:
    """Best point of a coarse log grid over the allowed box (for vectorised models).

    With k > 1, the k best points as a (k, 2) array (starts for a multi-start solve).
    """
    la = np.linspace(LOG_LO[0], LOG_HI[0] - 4, 48)
    ls = np.linspace(LOG_LO[1] + 2, LOG_HI[1] - 3, 48)
    aa, ss = np.meshgrid(la, ls, indexing="ij")
    v = np.asarray(fun(np.stack([aa.ravel(), ss.ravel()])))
    # relative mismatch: an absolute one cannot tell TT = 1e-4 from TT = 0
    tiny = 1e-300
    err = (np.abs(np.log(np.maximum(v[0], tiny)) - np.log(max(target[0], tiny)))
           + np.abs(np.log(np.maximum(v[1], tiny)) - np.log(max(target[1], tiny))))
    err = np.where(np.isfinite(err), err, np.inf)
    if k == 1:
        i = int(np.argmin(err))
        return np.array([aa.ravel()[i], ss.ravel()[i]])
    idx = np.argsort(err)[:k]
    return np.stack([aa.ravel()[idx], ss.ravel()[idx]], axis=1)


def solve(fun: Callable, target: np.ndarray, x0: np.ndarray, tol: float,
          jac_fun: Callable | None = None, max_iter: int = 60,
          j0: np.ndarray | None = None) -> Solution:
    """Damped Newton on ``fun(x) = target`` from ``x0``; ``fun`` maps (2,) -> (2,).

    ``jac_fun`` (vectorised, (2,k) -> (2,k)) supplies the slopes; ``fun`` itself when None.
    A Jacobian is reused (chord steps) while each step cuts the residual at least 4-fold,
    and recomputed otherwise; ``j0`` is a Jacobian to start with. Steps are clipped to the
    allowed box; a step that does not lower the residual is halved (up to 6 times) before
    the iteration gives up.
    """
    jf = jac_fun or fun
    x = np.clip(np.asarray(x0, float), LOG_LO, LOG_HI)
    v = np.asarray(fun(x), float)
    evals = 1
    r = v - target
    # Newton steps and the line search work on (ln TT, TR): TT falls exponentially with
    # thickness and coefficients, and its logarithm is close to linear in them, so nearly
    # opaque samples converge as well as clear ones. Convergence is judged on TT, TR.
    ln_t = np.log(max(target[0], 1e-300))

    def tres(vals):
        return np.array([np.log(max(vals[0], 1e-300)) - ln_t, vals[1] - target[1]])

    rt = tres(v)
    it = 0
    j = j0
    fresh = False
    while it < max_iter and np.max(np.abs(r)) > tol:
        it += 1
        if j is None:
            j = jacobian(jf, x)
            fresh = True
        jt = j * np.array([[1.0 / max(v[0], 1e-300)], [1.0]])
        try:
            step = -np.linalg.solve(jt, rt)
        except np.linalg.LinAlgError:
            step = -np.linalg.lstsq(jt, rt, rcond=None)[0]
        if not np.all(np.isfinite(step)):
            break
        norm = np.max(np.abs(step))
        if norm > MAX_STEP:
            step *= MAX_STEP / norm
        t = 1.0
        accepted = False
        for _ in range(7):
            xn = np.clip(x + t * step, LOG_LO, LOG_HI)
            vn = np.asarray(fun(xn), float)
            evals += 1
            rn = vn - target
            rtn = tres(vn)
            if np.all(np.isfinite(rtn)) and np.sum(rtn**2) < np.sum(rt**2):
                accepted = True
                break
            t *= 0.5
        if not accepted:
            if fresh:
                break
            j = None  # a stale Jacobian: recompute and try again
            continue
        if np.allclose(xn, x, rtol=0, atol=1e-12):
            x, v, r, rt = xn, vn, rn, rtn
            break
        if np.sum(rtn**2) > np.sum(rt**2) / 16.0:
            j = None  # slow progress: fresh slopes next time
        fresh = False
        x, v, r, rt = xn, vn, rn, rtn
    res = float(np.max(np.abs(r)))
    return Solution(x=x, values=v, residual=res, iterations=it, evaluations=evals,
                    converged=res <= tol)
