"""A region-of-attraction estimate by SOS: Van der Pol in reverse time.

    x1' = -x2,   x2' = x1 + (x1^2 - 1) x2        (the origin is stable; its basin is bounded
                                                  by the unstable limit cycle)

V(x) = x^T P x with A^T P + P A = -I (the linearisation). The largest level set {V <= rho}
on which dV/dt < 0 (except at 0) is found as one SOS program, linear in rho: dV/dt has no
zero but 0 in {V < rho}  <=  (V - rho) |x|^4 >= 0 on {dV/dt = 0}, i.e. (V - rho) |x|^4 -
lambda(x) dV/dt is SOS for some polynomial lambda (Parrilo's S-procedure, `add_nonneg_on`).
(With |x|^2 in place of |x|^4 the certificate is singular along directions the solver's kernel
does not name in small rationals, and sosdyn refuses to hand out its rho unproven.)
Sanity check: rho equals min V over the curve {dV/dt = 0, x != 0}, computed on a grid.
Usage: python 05_sos_region_of_attraction.py
"""
import numpy as np
from scipy.linalg import solve_continuous_lyapunov

import sosdyn as sd

x1, x2 = sd.variables("x1 x2")
f = [-x2, x1 + (x1**2 - 1) * x2]
A = np.array([[0.0, -1.0], [1.0, -1.0]])
P = solve_continuous_lyapunov(A.T, -np.eye(2))
V = P[0, 0] * x1**2 + 2 * P[0, 1] * x1 * x2 + P[1, 1] * x2**2
Vdot = V.directional_derivative(f, ["x1", "x2"])

prog = sd.SOSProgram("ROA")
rho = prog.new_var()
prog.add_nonneg_on((V - rho) * (x1**2 + x2**2) ** 2, eqs=[Vdot], degree=6, name="level set")
prog.maximize(rho)
sol = prog.solve(raise_on_failure=True)
rho_sos = sol.value(rho)
print(f"P = {P.round(4).tolist()}")
print(f"SOS estimate: rho = {rho_sos:.4f}")

# Known answer: the smallest V where dV/dt >= 0 (away from the origin), on a polar grid.
th, r = np.meshgrid(np.linspace(0, 2 * np.pi, 1500), np.linspace(0.05, 4, 1500))
X = np.column_stack([(r * np.cos(th)).ravel(), (r * np.sin(th)).ravel()])
vals, vdots = V(X), Vdot(X)
rho_grid = vals[vdots >= 0].min()
print(f"grid:         rho = {rho_grid:.4f}")
assert rho_sos <= rho_grid * (1 + 1e-3) and rho_sos >= 0.98 * rho_grid
