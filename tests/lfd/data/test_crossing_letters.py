"""The held-out crossing letters (issue 36): loads by name, is synthetic, ends at the origin, looks
like a pen-tablet log (0.1 px, 5 ms reports with gaps, rest at the goal), is what the seeded
generator writes, and crosses itself in every demo."""
import numpy as np
import pytest

import sosdyn as sd
from problems.crossing_letters import LETTERS, PERIOD_MS, generate
from sosdyn.lfd.data.crossing import find_crossings
from sosdyn.lfd.data.datasets import CROSSING_LETTERS, DATASETS, DATASETS_DIR, load_dataset


def test_every_letter_is_shipped_synthetic_and_held_apart():
    assert set(CROSSING_LETTERS) == set(LETTERS)
    names = [f"crossing_letters/{x}" for x in CROSSING_LETTERS]
    assert set(names) <= set(sd.dataset_names(synthetic=True))
    assert not set(names) & set(sd.dataset_names(synthetic=False))
    assert all(DATASETS[n].synthetic for n in names)
    assert "MIT License" in (DATASETS_DIR / "crossing_letters" / "LICENSE").read_text()
    assert "Synthetic, not recorded" in (DATASETS_DIR / "crossing_letters" / "README.md").read_text()


def test_g_loads_as_a_tablet_log():
    demos = load_dataset("crossing_letters/g")
    assert len(demos) == 7 and demos.dim == 2 and demos.units == "px"
    raw = np.loadtxt(DATASETS_DIR / "crossing_letters" / "g" / "demo_00.csv", delimiter=",", skiprows=1)
    assert np.allclose(demos[0].t, raw[:, 0] / 1000) and np.array_equal(demos[0].pos, raw[:, 1:])
    steps = np.diff(raw[:, 0])
    assert set(np.unique(steps)) <= {PERIOD_MS * k for k in range(1, 4)} and (steps > PERIOD_MS).any()
    for d in demos:
        assert np.array_equal(d.pos[-1], [0, 0])                  # the goal is the origin
        assert np.allclose(d.pos * 10, np.rint(d.pos * 10))        # 0.1 px resolution
        assert not np.array_equal(d.pos, np.rint(d.pos))           # not integer pixels (unlike crossing/)
        assert np.abs(d.pos[-20:]).max() < 2                       # resting near the goal


def test_the_shipped_files_are_what_the_seeded_generator_writes():
    data = generate()
    for letter in ("b", "four"):
        for k in (0, len(data[letter]) - 1):
            ms, xy = data[letter][k]
            raw = np.loadtxt(DATASETS_DIR / "crossing_letters" / letter / f"demo_{k:02d}.csv", delimiter=",",
                             skiprows=1)
            assert np.array_equal(raw[:, 0], ms) and np.allclose(raw[:, 1:], xy, atol=1e-9)


@pytest.mark.parametrize("letter", CROSSING_LETTERS)
def test_every_letter_crosses_itself_after_preprocessing(letter):
    demos, _ = sd.preprocess(load_dataset(f"crossing_letters/{letter}"))
    found = find_crossings(demos)
    assert {c.a for c in found if c.a == c.b} == set(range(len(demos)))
