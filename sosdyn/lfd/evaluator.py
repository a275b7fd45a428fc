"""Fast evaluation of a fitted CDSP field at one state, for control loops.

:meth:`sosdyn.lfd.cdsp.CDSP.predict` is vectorised over many states; for one state its
einsums, validation and error-state handling cost about 0.5 ms. :class:`StatePredictor`
computes the same numbers with everything that does not depend on x precomputed once:

    z = (x - x*) / s
    d = A z - b,     A = [L_1^-1; ...; L_K^-1]  (K n x n),   b_k = L_k^-1 mu_k     (S_k = L_k L_k^T)
    l_k = c_k - 1/2 |d_k|^2,    c_k = log pi_k - sum_i log L_k,ii - n/2 log 2 pi
    h = exp(l - max l) / sum exp(l - max l)
    xdot = s * (h^T C) z^E,      C reshaped to (K, n m),  z^E the m monomial values of z

which is the same sum as ``predict`` (the quadratic forms |L_k^-1 (z - mu_k)|^2 written as
|L_k^-1 z - L_k^-1 mu_k|^2), equal to it to rounding (about 1e-15 relative). Where every l_k
under- or overflows (|z| ~ 1e154 and up) the predictor falls back on the mixture's own
:meth:`~sosdyn.lfd.gmm.PositionMixture.responsibilities` (one-hot on the nearest component),
so the far-field behaviour is the same as ``predict``'s too.

A predictor is a snapshot of the model's arrays: refit or reload the model, then build a new one.
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from .gmm import PositionMixture


class StatePredictor:
    """xdot = f(x) at one state x of shape (n,), for a control loop; ``predictor(x)``.

    Built from a fitted model's arrays (:meth:`sosdyn.lfd.cdsp.CDSP.predictor` does this):
    goal x* (n,), scale s, the position mixture, coefficients C (K, n, m) and exponents E (m, n).
    """

    def __init__(self, goal: np.ndarray, scale: float, mixture: PositionMixture, C: np.ndarray,
                 exps: np.ndarray):
        inv, lognorm = mixture.factors()
        K, n, m = C.shape
        self.dim = n
        self._goal = np.array(goal, dtype=float)
        self._scale = float(scale)
        self._mixture = mixture
        self._A = np.ascontiguousarray(inv.reshape(K * n, n))
        self._b = np.einsum("kij,kj->ki", inv, mixture.means).reshape(K * n)
        self._c = np.array(lognorm, dtype=float)
        self._K = K
        self._C = np.ascontiguousarray(C.reshape(K, n * m))
        self._nm = (n, m)
        self._exps = np.array(exps, dtype=float)
        self._linear = bool(np.array_equal(self._exps, np.eye(n)))   # field degree 1: z^E = z

    def __call__(self, x) -> np.ndarray:
        """xdot (n,) at the state x (n,), in the data's units; the same numbers as
        ``model.predict(x[None])[0]``. Raises InputError for a wrong shape, NaN/inf, or a state
        so far away that the field overflows float."""
        x = np.asarray(x, dtype=float)
        if x.shape != (self.dim,) or not math.isfinite(x.sum()):
            raise InputError(f"x must be {self.dim} finite numbers (shape ({self.dim},)), got "
                             f"{'shape ' + str(x.shape) if x.shape != (self.dim,) else x}. Try: "
                             "model.predict(X) for many states at once.")
        z = (x - self._goal) / self._scale
        with np.errstate(over="ignore", invalid="ignore"):
            d = self._A @ z - self._b
            lj = self._c - 0.5 * (d * d).reshape(self._K, self.dim).sum(axis=1)
            top = lj.max()
            if math.isfinite(top):                   # no NaN, at least one finite l_k
                e = np.exp(lj - top)
                h = e / e.sum()
            else:
                h = self._mixture.responsibilities(z[None])[0]
            mono = z if self._linear else np.prod(z ** self._exps, axis=1)
            v = ((h @ self._C).reshape(self._nm) @ mono) * self._scale
        if not math.isfinite(v.sum()):
            raise InputError(f"x = {x} is so far from the data (scale {self._scale:.3g}) that the field "
                             "overflows float. Try: states within a few orders of magnitude of the "
                             "demonstrations.")
        return v
