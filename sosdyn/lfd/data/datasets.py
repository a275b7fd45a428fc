"""Demonstration sets shipped with sosdyn: :func:`load_dataset` and :func:`dataset_names`.

Real sets (recorded by others; ``dataset_names(synthetic=False)``): the files live in ``sosdyn/lfd/data/datasets/<set>/`` with their source repository's LICENSE
(copied verbatim), a README (provenance, units, caveats) and a manifest; values are as recorded
(no smoothing, no resampling, no unit change). Every set is MIT-licensed by its authors.

=============================  ====  =====  ======================  ========================
name                           dim   demos  units of x, y, z        time
=============================  ====  =====  ======================  ========================
robottasks/<task> (4 tasks)    3     9      cm (inferred)           k / 60 s (nominal)
pouring                        3     63     m (inferred)            k * 0.01 s
hammer                         3     10     m (inferred)            sample index: dt declared
cleaning/cleaning_1, _2        6     1      rad (inferred, joints)  recorded, ~0.035 s
crossing/<shape> (8, synth.)   2     7-8    px (y up, goal at 0)    logged ms, jittered
crossing_letters/<l> (6, syn.) 2     7      px (0.1 px, goal at 0)  5 ms reports, some lost
winding/<shape> (9, synth.)    2     7      px (y up, goal at 0)    logged ms, jittered
=============================  ====  =====  ======================  ========================

``crossing/<shape>`` (``ell``, ``e``, ``phi``, ``alpha``, ``gamma``, ``at``, ``pretzel``,
``cross``) is **synthetic**: hand-drawing-like mouse strokes that cross themselves or each
other, written by ``python -m problems crossing-shapes`` (seeded; its README says how and why).
``winding/<shape>`` (``spiral180``, ``spiral270``, ``spiral360``, ``hook``, ``G``, ``snail``,
``nearhook``, ``loop``, ``curl``) is synthetic the same way: strokes that wind around the goal, written by
``python -m problems winding-shapes``. ``crossing_letters/<letter>`` (``b``, ``h``, ``f``, ``g``,
``eight``, ``four``) is a second synthetic crossing set from another generator (sigma-lognormal
strokes, a pen-tablet log; ``python -m problems crossing-letters``), held out: models are tuned
on ``crossing`` only. :attr:`DatasetInfo.synthetic` marks them, and experiments on real data ask for
``dataset_names(synthetic=False)``.

Pose sets (robottasks, pouring) also hold an orientation quaternion ``qw, qx, qy, qz``: the loader
returns :class:`~sosdyn.lfd.data.pose.PoseDemonstrations` (positions and orientations, read as a pose
CSV is: :func:`~sosdyn.lfd.data.pose.load_pose_demos`, for :class:`~sosdyn.PoseCDSP`), or with
``positions_only=True`` the positions x, y, z alone as :class:`Demonstrations`.
``hammer`` has no time stamps (sample index): its time step is declared by ``dt`` (default
:data:`HAMMER_DT` = 0.01 s, an assumption announced by a warning unless ``dt`` is given).
The synthetic ``pick_and_place`` set of the source collection is not shipped.
"""

from __future__ import annotations

import difflib
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sosdyn.errors import InputError
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations, check_demonstrations
from sosdyn.lfd.data.pose import PoseDemonstrations, load_pose_demos

DATASETS_DIR = Path(__file__).resolve().parent / "datasets"
HAMMER_DT = 0.01        # s per sample, declared (the source has none; its loader uses dt = 1)
CROSSING_SHAPES = ("ell", "e", "phi", "alpha", "gamma", "at", "pretzel", "cross")
CROSSING_LETTERS = ("b", "h", "f", "g", "eight", "four")
WINDING_SHAPES = ("spiral180", "spiral270", "spiral360", "hook", "G", "snail", "nearhook", "loop", "curl")


@dataclass(frozen=True)
class DatasetInfo:
    """One shipped set: folder (below DATASETS_DIR), position columns, units as stated in its
    README, whether it holds orientations, and whether its ``t`` is a sample index."""

    folder: str
    columns: tuple[str, ...]
    units: str
    pose: bool = False
    index_time: bool = False
    note: str = ""
    time: str = "t"
    time_unit: float = 1.0
    synthetic: bool = False


_XYZ = ("x", "y", "z")
DATASETS = {
    **{f"robottasks/{task}": DatasetInfo(f"robottasks/{task}", _XYZ, "cm (inferred)", pose=True,
                                         note="Franka Panda kinesthetic demos, t = k/60 s (nominal)")
       for task in ("openbox", "bottle2shelf", "platestandingtolying", "pouring")},
    "pouring": DatasetInfo("pouring", _XYZ, "m (inferred)", pose=True,
                           note="63 real pouring demos (ImitationFlows); ends scatter up to 11 cm"),
    "hammer": DatasetInfo("hammer", _XYZ, "m (inferred)", index_time=True,
                          note="OptiTrack hammer strokes (CONDOR); t is the sample index"),
    **{f"cleaning/{m}": DatasetInfo(f"cleaning/{m}", tuple(f"q{i}" for i in range(1, 7)), "rad (inferred)",
                                    note="one joint-space demo (6 joints) of a cleaning motion")
       for m in ("cleaning_1", "cleaning_2")},
    **{f"crossing/{shape}": DatasetInfo(f"crossing/{shape}", ("x", "y"), "px", time="time_ms", time_unit=1e-3,
                                        synthetic=True, note="synthesised mouse strokes that cross (issue 28)")
       for shape in CROSSING_SHAPES},
    **{f"crossing_letters/{letter}": DatasetInfo(f"crossing_letters/{letter}", ("x", "y"), "px", time="time_ms",
                                                 time_unit=1e-3, synthetic=True,
                                                 note="held-out synthesised pen-tablet letters that cross (issue 36)")
       for letter in CROSSING_LETTERS},
    **{f"winding/{shape}": DatasetInfo(f"winding/{shape}", ("x", "y"), "px", time="time_ms", time_unit=1e-3,
                                       synthetic=True, note="synthesised mouse strokes that wind around the goal (issue 36)")
       for shape in WINDING_SHAPES},
}


def dataset_names(synthetic: bool | None = None) -> list[str]:
    """The names :func:`load_dataset` accepts, sorted; only the real (recorded) sets for
    ``synthetic=False``, only the synthesised ones for ``True``."""
    return sorted(k for k, info in DATASETS.items() if synthetic is None or info.synthetic == synthetic)


def dataset_info(name: str) -> DatasetInfo:
    """The :class:`DatasetInfo` of ``name``; InputError with the close names if unknown."""
    if not isinstance(name, str):
        raise InputError(f"a data set's name is one string, got {type(name).__name__} {name!r:.60}. Try: one of "
                         f"{', '.join(dataset_names())}; load several one by one.")
    if name not in DATASETS:
        close = difflib.get_close_matches(str(name), DATASETS, n=3, cutoff=0.4)
        hint = f"Did you mean {', '.join(close)}? " if close else ""
        raise InputError(f"Unknown data set {name!r}. {hint}Valid names: {', '.join(dataset_names())}.")
    return DATASETS[name]


def _read_csv(path: Path, info: DatasetInfo) -> tuple[np.ndarray, np.ndarray]:
    """(time column x its unit, positions) of a shipped CSV whose header names ``info.time``
    and ``info.columns``."""
    header = path.read_text().split("\n", 1)[0].strip().split(",")
    table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return table[:, header.index(info.time)] * info.time_unit, table[:, [header.index(c) for c in info.columns]]


def load_dataset(name: str, *, positions_only: bool | None = None, dt: float | None = None,
                 goal_tol: float | None = None) -> Demonstrations | PoseDemonstrations:
    """The demonstrations of the shipped set ``name`` (:func:`dataset_names`), checked by
    :func:`check_demonstrations` except for the ends, which are one rule applied after preprocessing
    (``pouring``'s ends scatter up to 11 cm: :func:`sosdyn.lfd.data.preprocess.preprocess` aligns
    them, and every model's ``fit`` refuses ends farther apart than ``goal_tol``, recorded here;
    None: 5 % of the data's diagonal).

    Positions as recorded, in the units of the set's README (``units`` names them, with
    "(inferred)" where the source does not state them); velocities estimated from positions
    (:meth:`Demonstration.from_positions`). Pose sets: :class:`PoseDemonstrations` (positions and
    orientations), or the positions alone with ``positions_only=True`` (module docstring). ``dt``: the time step (s) of
    an index-timed set (``hammer``; default :data:`HAMMER_DT`, announced); refused for sets with
    time stamps.
    """
    info = dataset_info(name)
    if positions_only not in (None, True, False):
        raise InputError(f"positions_only must be None, True or False, got {positions_only!r}.")
    if dt is not None and not info.index_time:
        raise InputError(f"{name} has time stamps; dt applies only to index-timed sets "
                         f"({', '.join(n for n, i in DATASETS.items() if i.index_time)}). Try: drop dt.")
    if info.index_time:
        if dt is None:
            warnings.warn(f"{name} has no time stamps (t = sample index): sample k is placed at k * {HAMMER_DT} s "
                          "(assumed). Pass dt=<s per sample> to declare another rate.", UserWarning, stacklevel=2)
        step = HAMMER_DT if dt is None else dt
        if isinstance(step, bool) or not isinstance(step, (int, float, np.number)) or not 0 < step < np.inf:
            raise InputError(f"dt must be a finite number > 0 (s per sample), got {dt!r}.")
    paths = sorted((DATASETS_DIR / info.folder).glob("demo_*.csv"))
    if info.pose and not positions_only:
        poses = load_pose_demos(paths, units=info.units, name=name)
        return PoseDemonstrations(poses.demos, name, info.units, poses.notes)
    demos = []
    for path in paths:
        t, pos = _read_csv(path, info)
        demos.append(Demonstration.from_positions(t * step if info.index_time else t, pos,
                                                  f"{name}/{path.name}"))
    return check_demonstrations(Demonstrations(demos, name, info.units, columns=info.columns), goal_tol=goal_tol,
                                ends=False)
