"""A Lyapunov function by SOS (SOSTOOLS' sosdemo2 system), then a sampled check of its decrease.

    x1' = -x1^3 - x1 x3^2,   x2' = -x2 - x1^2 x2,   x3' = -x3 - 3 x3/(x3^2 + 1) + 3 x1^2 x3

Find V(x) = sum of a_i x_i^2 with V - eps |x|^2 SOS and -(x3^2 + 1) dV/dt SOS (the factor
clears the rational term). Usage: python 04_sos_lyapunov.py
"""
import numpy as np

import sosdyn as sd

x1, x2, x3 = sd.variables("x1 x2 x3")
names = ["x1", "x2", "x3"]          # calculus takes variable names
# the field multiplied through by (x3^2 + 1) > 0: same sign of dV/dt, polynomial
d = x3**2 + 1
f_cleared = [(-x1**3 - x1 * x3**2) * d, (-x2 - x1**2 * x2) * d,
             (-x3 + 3 * x1**2 * x3) * d - 3 * x3]

prog = sd.SOSProgram("sosdemo2")
a = [prog.new_var() for _ in range(3)]
V = a[0] * x1**2 + a[1] * x2**2 + a[2] * x3**2
eps = 1.0
prog.add_sos(V - eps * (x1**2 + x2**2 + x3**2), name="V positive")
con = prog.add_sos(-V.directional_derivative(f_cleared, names), name="V decreasing")
sol = prog.solve(raise_on_failure=True)

coef = [sol.value(ai) for ai in a]
print("status:", sol.status, "verified:", sol.verified)
print(f"V = {coef[0]:.4f} x1^2 + {coef[1]:.4f} x2^2 + {coef[2]:.4f} x3^2")
print(sol.verify())

# Independent check with the true (rational) field at random states.
rng = np.random.default_rng(0)
X = rng.uniform(-3, 3, size=(20_000, 3))
f = np.column_stack([-X[:, 0]**3 - X[:, 0] * X[:, 2]**2, -X[:, 1] - X[:, 0]**2 * X[:, 1],
                     -X[:, 2] - 3 * X[:, 2] / (X[:, 2]**2 + 1) + 3 * X[:, 0]**2 * X[:, 2]])
Vdot = 2 * (X * np.asarray(coef) * f).sum(axis=1)
print(f"max dV/dt over {len(X)} random states: {Vdot.max():.3e}")
assert Vdot.max() <= 1e-9, "V does not decrease"
