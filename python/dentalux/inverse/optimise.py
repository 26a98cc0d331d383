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


def grid_start(fun: Callable, target: np.ndarray) -> np.ndarray:
    """Best point of a coarse log grid over the allowed box (for vectorised models)."""
    la = np.linspace(LOG_LO[0], LOG_HI[0] - 4, 48)
    ls = np.linspace(LOG_LO[1] + 2, LOG_HI[1] - 3, 48)
    aa, ss = np.meshgrid(la, ls, indexing="ij")
    v = np.asarray(fun(np.stack([aa.ravel(), ss.ravel()])))
    err = np.abs(v[0] - target[0]) + np.abs(v[1] - target[1])
    err = np.where(np.isfinite(err), err, np.inf)
    i = int(np.argmin(err))
    return np.array([aa.ravel()[i], ss.ravel()[i]])


def solve(fun: Callable, target: np.ndarray, x0: np.ndarray, tol: float,
          jac_fun: Callable | None = None, max_iter: int = 60) -> Solution:
    """Damped Newton on ``fun(x) = target`` from ``x0``; ``fun`` maps (2,) -> (2,).

    ``jac_fun`` (vectorised, (2,k) -> (2,k)) supplies the slopes; ``fun`` itself when None.
    Steps are clipped to the allowed box; a step that does not lower the residual is halved
    (up to 6 times) before the iteration gives up.
    """
    jf = jac_fun or fun
    x = np.clip(np.asarray(x0, float), LOG_LO, LOG_HI)
    v = np.asarray(fun(x), float)
    evals = 1
    r = v - target
    it = 0
    while it < max_iter and np.max(np.abs(r)) > tol:
        it += 1
        j = jacobian(jf, x)
        try:
            step = -np.linalg.solve(j, r)
        except np.linalg.LinAlgError:
            step = -np.linalg.lstsq(j, r, rcond=None)[0]
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
            if np.all(np.isfinite(rn)) and np.sum(rn**2) < np.sum(r**2):
                accepted = True
                break
            t *= 0.5
        if not accepted:
            break
        if np.allclose(xn, x, rtol=0, atol=1e-12):
            x, v, r = xn, vn, rn
            break
        x, v, r = xn, vn, rn
    res = float(np.max(np.abs(r)))
    return Solution(x=x, values=v, residual=res, iterations=it, evaluations=evals,
                    converged=res <= tol)
