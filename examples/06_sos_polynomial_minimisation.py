"""The global minimum of a polynomial by SOS, with a bound proven in exact arithmetic.

Six-hump camel: p = 4x^2 - 2.1x^4 + x^6/3 + xy - 4y^2 + 4y^4, global minimum -1.0316284535
at (+-0.0898, -+0.7126). max g s.t. p - g is SOS gives a lower bound, tight here;
`rigorous=True` backs it off until rational arithmetic proves p - g SOS exactly.
Usage: python 06_sos_polynomial_minimisation.py
"""
import numpy as np

import sosdyn as sd

x, y = sd.variables("x y")
p = 4 * x**2 - 2.1 * x**4 + x**6 / 3 + x * y - 4 * y**2 + 4 * y**4

prog = sd.SOSProgram("six-hump camel")
g = prog.new_var()
con = prog.add_sos(p - g)
prog.maximize(g)
sol = prog.solve(rigorous=True, raise_on_failure=True)

b = sol.bound
print(f"solver value   {b.solver_value:.10f}")
print(f"proven bound   {b.proven:.10f}   (p >= this everywhere, exactly)")
print(f"gap            {b.gap:.2e}, proof took {b.seconds:.2f} s")
print(f"certificate    p - g = z^T Q z, z = {len(con.basis)} monomials, Q {sol.gram_matrix(con).shape}")

# Known answer: the proven bound is below the true minimum and close to it.
true_min = -1.0316284535
grid = np.linspace(-2, 2, 801)
X = np.array(np.meshgrid(grid, grid)).reshape(2, -1).T
print(f"grid minimum   {p(X).min():.10f}   (true {true_min})")
assert b.proven <= true_min <= b.proven + 1e-5
