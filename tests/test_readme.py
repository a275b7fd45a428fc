"""The README's Python quickstart and its walk-through on the shipped data run as written, and
the picture it opens with exists."""
import importlib.util
import re
import shlex
import shutil
from pathlib import Path

import numpy as np
import pytest
from cli_support import run
from test_cli_poses import write_pose_csvs

import sosdyn as sd

from sosdyn.errors import SosdynError
from sosdyn.lfd.data import lasa

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
BLOCKS = re.findall(r"```python\n(.*?)```", README, flags=re.DOTALL)


def test_picture_and_sections():
    images = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", README)
    assert images and all((ROOT / p).is_file() for p in images)
    for heading in ("## Install", "## Five minutes with sosdyn", "## Accuracy on LASA (ds-opt protocol)"):
        assert heading in README


def test_sos_library_block_runs(capsys):
    block = next(b for b in BLOCKS if "SOSProgram" in b)
    scope = {}
    exec(compile(block, "README.md", "exec"), scope)  # noqa: S102 -- the README's own code, run as written
    sol, g = scope["sol"], scope["g"]
    # Motzkin with a multiplier: min 0, the printed value is a bound (whatever the solver's g)
    assert sol.verified and -1e-6 < sol.value(g) <= 0.0
    assert "optimal" in capsys.readouterr().out


def test_lasa_block_runs(tmp_path, monkeypatch):
    try:
        lasa.lasa_dir()
    except SosdynError as exc:
        pytest.skip(str(exc))
    monkeypatch.chdir(tmp_path)
    block = next(b for b in BLOCKS if "load_lasa" in b)
    scope = {}
    exec(compile(block, "README.md", "exec"), scope)  # noqa: S102 -- the README's own code, run as written
    model, traj = scope["model"], scope["traj"]
    assert model.verification_.passed and (tmp_path / "sshape.json").is_file()
    assert traj.pos.shape[1] == 2 and abs(traj.pos[-1] - [10, 5]).max() < 2.0   # heading to the moved goal


# ------------------------------------------------- the walk-through on the shipped data (steps 2-4)

SHELL = re.findall(r"```bash\n(.*?)```", README, flags=re.DOTALL)
WALK = README[README.index("**2. Your own demonstrations**"):README.index("**5. The SOS library")]


def readme_commands(text):
    """The ``sosdyn ...`` lines of the bash blocks in ``text``, comments stripped, as argv lists."""
    lines = [ln.split("  #")[0].strip() for block in re.findall(r"```bash\n(.*?)```", text, flags=re.DOTALL)
             for ln in block.splitlines()]
    return [shlex.split(ln)[1:] for ln in lines if ln.startswith("sosdyn ")]


def is_pose_command(argv) -> bool:
    """The walk-through's pose paragraph: commands on poses/ or pose.json (run by their own test)."""
    return any(a.startswith(("poses/", "pose.json")) for a in argv)


def is_second_order_command(argv) -> bool:
    """The walk-through's second-order paragraph: commands on o2.json (run by their own test)."""
    return any(a.startswith("o2.json") for a in argv)


@pytest.mark.slow
def test_walkthrough_second_order_commands(capsys, tmp_path, monkeypatch):
    """The second-order paragraph as written, on the shipped crossing set."""
    monkeypatch.chdir(tmp_path)
    commands = [c for c in readme_commands(WALK) if is_second_order_command(c)]
    assert [c[0] for c in commands] == ["fit", "plot", "rollout", "export"]
    for argv in commands:
        code, _, err = run(capsys, *argv)
        assert code == 0, (argv, err)
    model = sd.load_model("o2.json")
    assert isinstance(model, sd.SecondOrderCDSP) and model.certified_
    assert "inline bool acceleration(const double* x, const double* v, double* a" in (tmp_path / "o2.hpp").read_text()
    assert (tmp_path / "o2.png").read_bytes()[:4] == b"\x89PNG"
    rows = np.loadtxt("run_o2.csv", delimiter=",", skiprows=1)
    speed = np.linalg.norm(np.diff(rows[:, 1:], axis=0), axis=1) / np.diff(rows[:, 0])
    assert speed.max() <= 300 * 1.01                                                  # --max-speed 300


@pytest.mark.slow
def test_walkthrough_pose_commands(capsys, tmp_path, monkeypatch):
    """The pose paragraph as written, on pose CSVs of a known rotation system (tests/test_cli_poses.py)."""
    monkeypatch.chdir(tmp_path)
    write_pose_csvs(tmp_path / "poses")
    commands = [c for c in readme_commands(WALK) if is_pose_command(c)]
    assert [c[0] for c in commands] == ["fit", "export", "plot", "rollout"]
    for argv in commands:
        code, _, err = run(capsys, *argv)
        assert code == 0, (argv, err)
    model = sd.load_model("pose.json")
    assert isinstance(model, sd.PoseCDSP) and model.certified_ and model.cdsp_.units_ == "m"
    assert "def predict_pose(" in (tmp_path / "pose_model.py").read_text()
    assert (tmp_path / "pose.png").read_bytes()[:4] == b"\x89PNG"
    run_pose = sd.load_demos(tmp_path / "run_pose.csv")[0]
    np.testing.assert_allclose(run_pose.pos[-1], model.goal_pos_, atol=1e-2)     # heading to the goal pose


def test_shipped_example_data_is_what_its_generator_writes(tmp_path):
    spec = importlib.util.spec_from_file_location("make_reach", ROOT / "examples/data/make_reach.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    for path in module.main(tmp_path):
        assert path.read_bytes() == (ROOT / "examples/data/reach" / path.name).read_bytes(), path.name


def test_walkthrough_runs_on_the_shipped_data(capsys, tmp_path, monkeypatch):
    """Steps 2-4 as written: fit the ms-stamped 3-D logs, plot, roll out, export, and the Python block."""
    data = tmp_path / "examples" / "data"
    data.mkdir(parents=True)
    shutil.copytree(ROOT / "examples/data/reach", data / "reach")
    monkeypatch.chdir(tmp_path)
    commands = [c for c in readme_commands(WALK) if not is_pose_command(c) and not is_second_order_command(c)]
    assert [c[0] for c in commands] == ["fit", "fit", "plot", "rollout", "export", "export"]
    for argv in commands:
        code, _, err = run(capsys, *argv)
        assert code == 0, (argv, err)
    model = sd.load_model("reach.json")
    assert model.dim_ == 3 and model.units_ == "m" and model.verification_.passed
    assert model.dt_ == pytest.approx(0.01)                   # 100 Hz: milliseconds read as such
    assert (tmp_path / "reach.png").read_bytes()[:4] == b"\x89PNG"
    run_csv = np.loadtxt("run.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(run_csv[-1, 1:], [0.35, -0.05, 0.25], atol=5e-3)     # the moved goal
    steps = np.linalg.norm(np.diff(run_csv[:, 1:], axis=0), axis=1)
    jump = int(np.argmax(steps))
    assert run_csv[jump + 1, 0] == pytest.approx(1.0) and steps[jump] > 0.04            # the push at t = 1
    assert np.delete(steps, jump).max() / model.dt_ <= 0.3 * 1.01                        # --max-speed 0.3
    assert "max_speed = 0.3;" in (tmp_path / "reach_field.hpp").read_text()
    block = next(b for b in BLOCKS if "predictor(max_speed" in b)
    scope = {}
    exec(compile(block, "README.md", "exec"), scope)  # noqa: S102 -- the README's own code, run as written
    assert np.linalg.norm(scope["xdot"]) <= 0.3 * (1 + 1e-12)
    np.testing.assert_allclose(scope["traj"].pos[-1], [0.35, -0.05, 0.25], atol=5e-3)


def test_install_starts_with_the_venv_and_states_measured_times():
    """A newcomer's first command installs (the old README opened with the 43-minute `make run`),
    and `make test`'s time is the one measured on 2 cores."""
    block = re.search(r"## Install\n\n```bash\n(.*?)```", README, flags=re.DOTALL).group(1)
    lines = [ln for ln in block.splitlines() if ln.startswith("make ")]
    assert [ln.split()[1] for ln in lines] == ["venv", "run", "test"]
    assert re.search(r"\d+ (s|min) measured", lines[1])
    assert re.search(r"\d+(\.\d+)? min measured on 2 cores", lines[2])

