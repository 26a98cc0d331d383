"""Smoothness across bands for a spectral ``fit --readings`` (``--smooth WEIGHT``).

Without it each band is fitted on its own. With it the fit also minimises WEIGHT times the
squared second differences of log μa and log μs across the bands, each a divided difference
scaled to a 10 nm spacing (so a gap in the bands is no kink): residuals are in units of the
readings' spread, so WEIGHT 1 makes a second difference of 1 in log μ (a bend by a factor e
over 10 nm) cost as much as a reading one standard deviation off. The data residuals stay
independent per band (one perturbed evaluation per parameter still gives every band's
derivative); the penalty couples the bands, so the Levenberg–Marquardt step is taken over
all of them at once, and the parameters' covariance is that of the penalised problem.
"""

from __future__ import annotations

import numpy as np

#: the spacing a second difference is scaled to [nm]
SPACING_NM = 10.0


def penalty(bands, params: int, weight: float) -> np.ndarray:
    """The penalty's rows acting on theta (bands, params) raveled: sqrt(weight) times the
    scaled second difference of each parameter at each inner band."""
    lam = np.asarray(bands, float)
    nb = lam.size
    rows = []
    for i in range(1, nb - 1):
        h1, h2 = (lam[i] - lam[i - 1]) / SPACING_NM, (lam[i + 1] - lam[i]) / SPACING_NM
        c = (2.0 / (h1 + h2)) * np.array([1.0 / h1, -(1.0 / h1 + 1.0 / h2), 1.0 / h2])
        for j in range(params):
            row = np.zeros(nb * params)
            row[[(i - 1) * params + j, i * params + j, (i + 1) * params + j]] = c
            rows.append(row)
    if not rows:
        return np.zeros((0, nb * params))
    return np.sqrt(weight) * np.array(rows)


def _full(jac) -> np.ndarray:
    """J^T J of block-independent residuals as one matrix over every band's parameters."""
    nb, _, k = jac.shape
    out = np.zeros((nb * k, nb * k))
    for b in range(nb):
        out[b * k:(b + 1) * k, b * k:(b + 1) * k] = jac[b].T @ jac[b]
    return out


def lm(obj, theta, step, iterations, lo, hi, pen, jacobian):
    """Levenberg–Marquardt over every band at once with the penalty rows ``pen``; returns
    theta, residuals, prediction, error, Jacobian (as readings_fit._lm)."""
    shape = theta.shape

    def total(r, th):
        return float(np.sum(r * r) + np.sum((pen @ th.ravel()) ** 2))

    r, pred, err = obj.residuals(theta)
    cost, lam = total(r, theta), 1e-2
    for it in range(iterations):
        jac = jacobian(obj, theta, r, step, lo, hi)
        a = _full(np.nan_to_num(jac)) + pen.T @ pen
        grad = (np.einsum("bmi,bm->bi", np.nan_to_num(jac), np.nan_to_num(r)).ravel()
                + pen.T @ (pen @ theta.ravel()))
        damp = a + lam * np.diag(np.maximum(np.diag(a), 1e-9))
        delta = np.clip(-np.linalg.pinv(damp) @ grad, -2.0, 2.0).reshape(shape)
        trial = np.clip(theta + delta, lo, hi)
        r_t, pred_t, err_t = obj.residuals(trial)
        cost_t = total(r_t, trial)
        if cost_t < cost:
            theta, r, pred, err, cost, lam = trial, r_t, pred_t, err_t, cost_t, lam / 5.0
        else:
            lam *= 10.0
        if it >= 1 and np.all(np.abs(delta) < 1e-3):
            break
    return theta, r, pred, err, jacobian(obj, theta, r, step, lo, hi)


def block_covariance(jac, pen) -> np.ndarray:
    """Each band's (params, params) block of the penalised problem's covariance."""
    nb, _, k = jac.shape
    cov = np.linalg.pinv(_full(np.nan_to_num(jac)) + pen.T @ pen)
    return np.array([cov[b * k:(b + 1) * k, b * k:(b + 1) * k] for b in range(nb)])
