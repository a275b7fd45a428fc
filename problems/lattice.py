"""The plot lattice: the field of a model cached on the grid its streamline plot uses."""
from __future__ import annotations

import numpy as np

from sosdyn.report.figures import data_bounds

from .jsonio import rounded
from .settings import EvalConfig, Shape, load_shape


def plot_bounds(demos, reproductions=(), pad=0.1) -> list[float]:
    """The square box :func:`sosdyn.report.figures.streamlines` draws by default."""
    box = data_bounds([d.pos for d in demos] + [np.asarray(r) for r in reproductions]
                      + [np.asarray(demos.goal)[None, :]], pad=pad, square=True)
    return [float(v) for v in box]


def lattice_points(bounds, grid: int) -> np.ndarray:
    """The ``grid`` x ``grid`` points over ``bounds`` (x fastest), as the streamline plot uses."""
    gx = np.linspace(bounds[0], bounds[1], grid)
    gy = np.linspace(bounds[2], bounds[3], grid)
    GX, GY = np.meshgrid(gx, gy)
    return np.column_stack([GX.ravel(), GY.ravel()])


def field_on_lattice(model, bounds, grid) -> dict:
    """``{"bounds", "grid", "V"}``: ``model.predict`` on the lattice, rounded for JSON."""
    V = model.predict(lattice_points(bounds, grid))
    return {"bounds": list(bounds), "grid": int(grid), "V": rounded(V)}


class CachedField:
    """``predict`` for a streamline plot from a field cached on its lattice.

    :func:`sosdyn.report.figures.streamlines` evaluates ``predict`` on the ``grid`` x
    ``grid`` lattice over ``bounds`` (x fastest); this returns the cached values for exactly
    that lattice and refuses any other points.
    """

    def __init__(self, spec: dict):
        self.bounds, self.grid = spec["bounds"], int(spec["grid"])
        self.V = np.array(spec["V"], dtype=float)

    def __call__(self, X):
        if X.shape != (self.grid**2, 2) or not np.allclose(X, lattice_points(self.bounds, self.grid)):
            raise ValueError("CachedField only answers on its own lattice")
        return self.V


def field_panel(entry: dict | None, shp: Shape, config: EvalConfig, title: str) -> dict | None:
    """The streamline panel (:func:`sosdyn.report.figures.streamline_panel`) of an entry whose
    field is cached on its lattice; None for a failed entry or one without a cached field."""
    if not entry or entry.get("status") != "ok" or "field" not in entry.get("plot", {}):
        return None
    demos = load_shape(shp, config)
    fld = entry["plot"]["field"]
    return {"predict": CachedField(fld), "demos_pos": [d.pos for d in demos],
            "reproductions": entry["plot"]["reproductions"], "goal": demos.goal,
            "bounds": fld["bounds"], "grid": fld["grid"], "title": title}
