"""Settings of the CDSP experiments: paths, constants, the paper's shapes, the compared methods,
the evaluation config.

"Method" here means one of the compared approaches (CDSP-ICA, DMP, ...); the integrator of a
rollout is called the integrator, and CDSP's ``solver_method`` is CDSP's own setting.
"""
from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import sosdyn as sd
from sosdyn.evaluation.baselines import CLFDM, DMP, GMR

REPO = Path(__file__).resolve().parents[1]
REPORTS = REPO / "reports"
CACHE = REPORTS / "cache"
FIGURES = REPORTS / "figures"
BENCH = REPORTS / "bench"
SEED = 0
GAMMA = 0.1   # contraction rate (1/s); smaller rates certify more accurate fields
CACHE_VERSION = 4


# ------------------------------------------------------------------ shapes

@dataclass(frozen=True)
class Shape:
    """A LASA shape with the paper's per-shape settings: K Gaussians and DMP basis functions."""

    name: str
    K: int = 6
    dmp_basis: int = 25


#: The paper's four shapes (section 3): K = CLF-DM's basis count, DMP 25/35/25/35.
PAPER_SHAPES = (Shape("BendedLine", 6, 25), Shape("DoubleBendedLine", 7, 35),
                Shape("Leaf_1", 6, 25), Shape("Leaf_2", 6, 35))
_PAPER = {s.name: s for s in PAPER_SHAPES}


def shape(name: str, K: int | None = None) -> Shape:
    """The Shape ``name`` (paper settings when known, else K = 6 and 25 DMP basis functions)."""
    base = _PAPER.get(name, Shape(name))
    return base if K is None else dataclasses.replace(base, K=K)


# ------------------------------------------------------------------ methods

_ESTIMATORS = {"cdsp": sd.CDSP, "GMR": GMR, "DMP": DMP, "CLF-DM": CLFDM}


@dataclass(frozen=True)
class Method:
    """A method of the comparison: ``factory(shape, quick)`` builds the unfitted model."""

    name: str
    description: str
    settings: Callable[[Shape, bool], dict]
    kind: str                 # "cdsp", "autonomous" (GMR, CLF-DM) or "dmp"
    plot_field: bool = False  # cache the field on the plot lattice (Fig. 1, LASA grid)

    def factory(self, shp: Shape, quick: bool = False):
        cls = _ESTIMATORS["cdsp" if self.kind == "cdsp" else self.name]
        return cls(**self.settings(shp, quick))


def _cdsp(metric_degree=0, field_degree=1, solver_method="alternating", metric="learned"):
    def settings(shp: Shape, quick: bool) -> dict:
        out = dict(n_components=shp.K, metric_degree=metric_degree, field_degree=field_degree,
                   gamma=GAMMA, metric=metric, solver_method=solver_method, max_iter=20, metric_prox=0.0,
                   corrective_rounds=0, warp="none", random_state=SEED,   # the paper's fit: no refits, no warp,
                   gating="posterior", speed_floor="none")                 # its weights, no speed floor
        if quick:
            out.update(max_samples=400, max_iter=4, verify_samples=2000)
        return out
    return settings


def _default(shp: Shape, quick: bool) -> dict:
    """``CDSP()`` as a user gets it: every parameter at its default."""
    return dict(max_samples=400, max_iter=4, verify_samples=2000) if quick else {}


def _gmr(shp: Shape, quick: bool) -> dict:
    return dict(n_components=shp.K, random_state=SEED)


def _dmp(shp: Shape, quick: bool) -> dict:
    return dict(n_weights_per_dim=shp.dmp_basis)


def _clfdm(shp: Shape, quick: bool) -> dict:
    out = dict(n_components=shp.K, n_asymmetric=6, random_state=SEED)   # L: the baseline's default
    if quick:
        out.update(n_init=1, max_iter=100)
    return out


METHODS: dict[str, Method] = {m.name: m for m in (
    # A CDSP method's description says what it stands for; what it is (sub-systems, metric,
    # solver, warp, refits) is written from its parameters (problems.results.cdsp_summary).
    Method("CDSP", "The default model, as a user gets it: CDSP() with no arguments.", _default, "cdsp",
           plot_field=True),
    Method("CDSP (paper)", "The paper's formulation, fitted with our solver.", _cdsp(2, 1, "alternating"),
           "cdsp"),
    Method("CDSP-ICA", "The LPV-DS-like model: GMM-weighted sub-systems sharing one quadratic Lyapunov "
           "matrix.", _cdsp(0, 1, "ica"), "cdsp", plot_field=True),
    Method("CDSP-cubic", "The paper's general model class.", _cdsp(2, 3, "ica"), "cdsp", plot_field=True),
    Method("SEDS-like", "A quadratic Lyapunov function V = z^T z, as in SEDS.",
           _cdsp(0, 1, "alternating", "identity"), "cdsp"),
    Method("GMR", "Gaussian mixture regression on [x, xdot] (same K and EM seed); no stability "
           "guarantee.", _gmr, "autonomous"),
    Method("DMP", "Dynamic movement primitives, one per demonstration (time-indexed; "
           "25/35/25/35 basis functions as in the paper).", _dmp, "dmp"),
    Method("CLF-DM", "GMR nominal field + learned WSAQF control Lyapunov function with online "
           "correction (Khansari-Zadeh & Billard 2014); K Gaussians, L = 6 asymmetric terms.",
           _clfdm, "autonomous"),
)}
METHOD_ORDER = tuple(METHODS)
#: The method the streamline figures show (Fig. 1, the per-shape pages): the default CDSP().
DEFAULT_METHOD = "CDSP"

#: What the autonomous methods are integrated with (results["methods"][*]["settings"]).
INTEGRATOR_NOTE = "LSODA, rtol 1e-6, atol 1e-8 (BDF if LSODA exceeds its budget)"


# ------------------------------------------------------------------ evaluation config

@dataclass(frozen=True)
class EvalConfig:
    """How a fitted model is scored (part of the cache key).

    ``n_demos``/``subsample`` shrink the data (tests); ``n_grid`` x ``n_grid`` starts for
    grid convergence (batched for autonomous models); ``push_amp``/``goal_amp``: event
    amplitudes as a fraction of the data's bounding-box diagonal, at ``at_frac`` of each
    demo; a perturbed run (and a reproduction drawn in a figure) lasts ``duration_factor`` x
    its demonstration, doubled until it ends within ``goal_tol`` (mm) of its goal, at most
    ``max_duration_factor`` x (:func:`sosdyn.evaluation.reproduction.rollout_to_goal`);
    ``field_grid``: lattice of the cached field for streamline plots.
    """

    quick: bool = False
    n_demos: int | None = None
    subsample: int = 1
    n_grid: int = 5
    push_amp: float = 0.1
    goal_amp: float = 0.1
    at_frac: float = 0.3
    duration_factor: float = 1.5
    max_duration_factor: float = 20.0
    goal_tol: float = 1.0
    field_grid: int = 70
    seed: int = SEED

    def key(self) -> dict:
        return dataclasses.asdict(self)


def load_shape(shp: Shape, config: EvalConfig):
    """The shape's demonstrations, reduced per the config."""
    demos = sd.load_lasa(shp.name)
    if config.n_demos:
        demos = demos[:config.n_demos]
    if config.subsample > 1:
        demos = demos.subsample(config.subsample)
    return demos
