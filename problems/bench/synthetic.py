"""Synthetic n-D demonstrations from a globally stable nonlinear system (for the scaling sweeps).

    xdot = -D x + S x / (1 + |x|^2) - 0.2 x^3 (element-wise cube),   D = diag(0.5 .. 1.5), S skew

d|x|^2/dt = -2 x^T D x - 0.4 sum x_i^4 < 0, so every trajectory converges to 0; the rotation S
bends the paths (a curved, non-linear flow like handwriting). The goal is moved to ``goal``.
"""
from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from sosdyn.lfd import Demonstration, Demonstrations


def system(n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    D = np.diag(np.linspace(0.5, 1.5, n))
    A = rng.normal(size=(n, n))
    S = 2.0 * (A - A.T)

    def f(x):
        x = np.asarray(x, dtype=float)
        r2 = np.sum(x * x, axis=-1, keepdims=True)
        return -x @ D.T + (x @ S.T) / (1.0 + r2) - 0.2 * x**3
    return f


def demos(n: int, n_demos: int = 7, samples_per_demo: int = 1000, duration: float = 8.0,
          radius: float = 3.0, scale: float = 10.0, seed: int = 0) -> Demonstrations:
    """``n_demos`` trajectories from points on a sphere of ``radius`` (units: ``scale``), to rest."""
    f = system(n, seed)
    rng = np.random.default_rng(seed + 1)
    goal = rng.uniform(-1, 1, size=n) * scale
    out = []
    t = np.linspace(0.0, duration, samples_per_demo)
    for i in range(n_demos):
        x0 = rng.normal(size=n)
        x0 *= radius / np.linalg.norm(x0)
        sol = solve_ivp(lambda _t, x: f(x), (0, duration), x0, t_eval=t, rtol=1e-7, atol=1e-9)
        X = sol.y.T
        out.append(Demonstration(t, X * scale + goal, f(X) * scale, f"synthetic n={n} #{i}"))
    return Demonstrations(out, f"synthetic-{n}d", "u")
