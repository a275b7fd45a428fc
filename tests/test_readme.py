"""The README's Python quickstart runs as written, and the picture it opens with exists."""
import re
from pathlib import Path

import pytest

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
    assert sol.status == "optimal" and abs(sol.value(g)) < 1e-6      # Motzkin with a multiplier: 0
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
