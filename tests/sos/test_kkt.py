"""The memory estimate follows the sparsity of the KKT factor (sosdyn.sos.kkt), checked against
hand counts and against the peak memory a solve really takes."""
import json
import subprocess
import sys

import pytest

import sosdyn as sd
from sosdyn.sos import kkt
from sosdyn.sos.backends import BASE_BYTES, solver_bytes
from sosdyn.sos.kkt import factor_entries

MiB = 2**20


def broyden(n):
    """Broyden tridiagonal: sum_i ((3 - 2 x_i) x_i - x_{i-1} - 2 x_{i+1} + 1)^2, minimum 0."""
    xs = [0] + list(sd.variables(" ".join(f"x{i}" for i in range(n)))) + [0]
    return sum(((3 - 2 * xs[i]) * xs[i] - xs[i - 1] - 2 * xs[i + 1] + 1) ** 2 for i in range(1, n + 1))


def lower_bound_program(p, **kw):
    prog = sd.SOSProgram()
    g = prog.new_var()
    prog.add_sos(p - g, **kw)
    prog.maximize(g)
    return prog, g


def test_one_dense_block_is_one_dense_group():
    # basis 1, x, y, x^2, xy, y^2 (svec 21) over the 15 monomials of degree <= 4; g touches the
    # constant's row: 21*22/2 + 21*15 (block) + 1*1 (g) + 15*16/2 (the rows, all linked) = 667
    x, y = sd.variables("x y")
    prog, _ = lower_bound_program(x**4 + y**4 + 1)
    assert factor_entries(prog.compile()) == 667


def test_broyden_chain_is_estimated_by_its_blocks_not_as_one_dense_group():
    # 58 clique blocks of 10 x 10 (svec 55) along a chain: was "needs about 1.0 GiB" (one dense
    # group of D = 58 * 55 + rows); the factor of a chain grows linearly with it
    f31 = factor_entries(lower_bound_program(broyden(31), sparsity="correlative")[0].compile())
    prog, g = lower_bound_program(broyden(60), sparsity="correlative")
    assert 1.9 < factor_entries(prog.compile()) / f31 < 2.1          # 58 blocks against 29
    with sd.limits(max_bytes=512 * MiB):
        assert solver_bytes(prog.compile(), "CLARABEL", "direct") < 64 * MiB
        sol = prog.solve(scale=False)
        assert -1e-4 <= sol.value(g) <= 0.0                        # solved within the estimate (minimum 0)


MEASURE = r"""
import json, os, sys
import sosdyn as sd
from sosdyn.sos.backends import solver_bytes
sys.path.insert(0, os.getcwd())
from tests.sos.test_kkt import broyden, lower_bound_program
def status_kib(key):
    return next(int(line.split()[1]) for line in open("/proc/self/status") if line.startswith(key))
x, y = sd.variables("x y")
out = {}
for name, (prog, g) in [("sparse", lower_bound_program(broyden(60), sparsity="correlative")),
                        ("dense", lower_bound_program((1 + x**2 + y**2) ** 8))]:
    est = solver_bytes(prog.compile(), "CLARABEL", "direct")
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")                                 # resets the peak (VmHWM) to the current RSS
    rss = status_kib("VmRSS:")
    prog.solve(scale=False, max_iter=3)
    out[name] = (est, 1024 * (status_kib("VmHWM:") - rss))
print(json.dumps(out))
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads and resets the peak in /proc/self")
def test_estimate_is_above_the_measured_peak_and_not_far_above_it():
    # a fresh process: the peak resident memory (VmHWM, reset before each solve) a solve adds over
    # what the process held before it
    run = subprocess.run([sys.executable, "-c", MEASURE], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    got = json.loads(run.stdout)
    for est, measured in got.values():
        assert measured <= est <= BASE_BYTES + 8 * max(measured, MiB)
    assert got["dense"][1] > 3 * got["sparse"][1]    # measured: about 58 MiB and 7 MiB


def test_a_long_elimination_stops_at_an_upper_bound(monkeypatch):
    # past ELIMINATION_WORK the rows not yet eliminated are counted dense: never below the count
    data = lower_bound_program(broyden(31), sparsity="correlative")[0].compile()
    exact = factor_entries(data)
    monkeypatch.setattr(kkt, "ELIMINATION_WORK", 0.0)
    m = data.A_eq.shape[0]
    assert exact < factor_entries(data) <= exact + m * (m + 1) / 2
