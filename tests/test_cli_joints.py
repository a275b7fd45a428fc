"""From a 7-joint log to a smooth C++ controller with the plain command-line defaults (issue 34 item 2):
``sosdyn fit`` on the joint CSVs, ``sosdyn export --to cpp``, compiled, then rolled out from starts
0.2-0.3 rad off every demonstration's start (each joint moved by +-0.2..0.3 rad): every joint's
acceleration and velocity stay within a Franka Panda's limits. The same for ``sosdyn rollout``."""
from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest

from problems.demo7d import demonstrations
from sosdyn.cli import main

#: Franka Panda joint limits (datasheet): acceleration (rad/s^2) and velocity (rad/s) per joint.
ACC_MAX = np.array([15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0])
VEL_MAX = np.array([2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61])
JOINTS = [f"panda_joint{i}" for i in range(1, 8)]
DT, DURATION, OFFSETS = 0.001, 8.0, 4      # Euler step (s), rollout (s), off-starts per demonstration

MAIN = """#include "model.hpp"
#include <cmath>
#include <cstdio>
// Explicit Euler x += dt f(x) from each start read on stdin; per joint the peak |v| and |(v_k - v_k-1) / dt|.
int main() {
  constexpr int N = cdsp_model::N;
  const double dt = %r;
  const int steps = %d;
  double x[N], v[N], prev[N], vmax[N] = {0}, amax[N] = {0};
  for (;;) {
    for (int i = 0; i < N; ++i) if (std::scanf("%%lf", &x[i]) != 1) goto done;
    for (int k = 0; k < steps; ++k) {
      if (!cdsp_model::predict(x, v)) return 2;
      for (int i = 0; i < N; ++i) {
        vmax[i] = std::fmax(vmax[i], std::fabs(v[i]));
        if (k > 0) amax[i] = std::fmax(amax[i], std::fabs(v[i] - prev[i]) / dt);
        prev[i] = v[i];
        x[i] += dt * v[i];
      }
    }
  }
done:
  for (int i = 0; i < N; ++i) std::printf("%%.9g %%.9g\\n", vmax[i], amax[i]);
  return 0;
}
""" % (DT, int(DURATION / DT))


def off_starts(demos, seed=0):
    """Per demonstration OFFSETS starts: its first sample with every joint moved by +-U(0.2, 0.3) rad."""
    rng = np.random.default_rng(seed)
    return np.array([d.pos[0] + rng.choice([-1.0, 1.0], 7) * rng.uniform(0.2, 0.3, 7)
                     for d in demos for _ in range(OFFSETS)])


def cli(*argv) -> None:
    """``sosdyn ARGV`` in-process; it must succeed."""
    try:
        main([str(a) for a in argv])
    except SystemExit as exc:
        assert not exc.code, f"sosdyn {' '.join(map(str, argv))} exited with {exc.code}"


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    """The 7-joint task of problems.demo7d (5 noisy demonstrations at 50 Hz) as CSV logs, fitted by
    ``sosdyn fit`` with its defaults: (folder, demonstrations, model file)."""
    folder = tmp_path_factory.mktemp("joints")
    demos = demonstrations(rate=50.0)
    for k, d in enumerate(demos):
        rows = [",".join(["t", *JOINTS])] + [",".join(f"{v:.6f}" for v in (t, *q)) for t, q in zip(d.t, d.pos)]
        (folder / f"reach_{k + 1}.csv").write_text("\n".join(rows) + "\n")
    cli("fit", *sorted(folder.glob("*.csv")), "--columns", ",".join(JOINTS), "--out", folder / "model.json")
    return folder, demos, folder / "model.json"


@pytest.mark.slow
def test_cpp_controller_from_a_joint_log_stays_within_the_panda_limits(fitted):
    folder, demos, model = fitted
    cli("export", model, "--to", "cpp", "--out", folder / "model.hpp")
    if shutil.which("g++") is None:
        pytest.skip("g++ is not on PATH")
    (folder / "main.cpp").write_text(MAIN)
    subprocess.run(["g++", "-std=c++17", "-O2", "-o", str(folder / "main"), str(folder / "main.cpp")],
                   check=True, capture_output=True, text=True, cwd=folder)
    starts = off_starts(demos)
    res = subprocess.run([str(folder / "main")], input="\n".join(" ".join(repr(float(v)) for v in x) for x in starts),
                         capture_output=True, text=True, check=True)
    vmax, amax = np.array([[float(v) for v in line.split()] for line in res.stdout.splitlines()]).T
    assert np.all(amax <= ACC_MAX), amax / ACC_MAX
    assert np.all(vmax <= VEL_MAX), vmax / VEL_MAX
    assert amax.max() > 0.05 * ACC_MAX.max()          # the rollouts moved


@pytest.mark.slow
def test_cli_rollouts_from_off_starts_stay_within_the_panda_limits(fitted):
    """``sosdyn rollout`` (the model's own step) from a few of the same starts, read back from its CSV."""
    folder, demos, model = fitted
    for k, x0 in enumerate(off_starts(demos)[::OFFSETS]):
        out = folder / f"rollout_{k}.csv"
        cli("rollout", model, "--start", ",".join(repr(float(v)) for v in x0), "--duration", DURATION,
            "--dt", 0.002, "--out", out)
        data = np.loadtxt(out, delimiter=",", skiprows=1)
        t, q = data[:, 0], data[:, 1:8]
        v = np.diff(q, axis=0) / np.diff(t)[:, None]
        a = np.diff(v, axis=0) / np.diff(t)[1:, None]
        assert np.all(np.abs(a).max(axis=0) <= ACC_MAX), np.abs(a).max(axis=0) / ACC_MAX
        assert np.all(np.abs(v).max(axis=0) <= VEL_MAX), np.abs(v).max(axis=0) / VEL_MAX
