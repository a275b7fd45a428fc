"""The figure of any fitted model (``sosdyn plot``), drawn from what the model itself says it shows
(:meth:`~sosdyn.lfd.model.base.MotionModel.reproductions`), by the data's shape, never by the
model's family: rollouts with orientations are pose paths with frames; else a 2-D model is drawn
with its velocity field's streamlines when it has one (first order), a 3-D one as trajectories with
their projections, a higher-dimensional one as time series. The axes carry the model's column
names and units.
"""
from __future__ import annotations

from pathlib import Path

from matplotlib.figure import Figure

from .poses import pose_paths
from .streamlines import streamlines
from .trajectories import time_series, trajectories_3d


def model_figure(view, title: str) -> Figure:
    """The figure of ``view`` (a :class:`~sosdyn.lfd.model.base.Reproductions`) titled ``title``."""
    if view.runs and getattr(view.runs[0], "quat", None) is not None:
        return pose_paths(title, [], view.demos, view.runs, view.goal, view.units,
                          [Path(d.source).stem for d in view.demos], names=view.names)
    demos, runs, n = [d.pos for d in view.demos], [r.pos for r in view.runs], len(view.goal)
    if n == 2:
        return streamlines(None, view.field, demos, runs, view.goal, title=title, units=view.units, names=view.names)
    if n == 3:
        return trajectories_3d(demos, runs, view.goal, title=title, units=view.units, names=view.names)
    return time_series([(r.t, r.pos) for r in view.runs], view.goal, view.units, title,
                       demos=[(d.t - d.t[0], d.pos) for d in view.demos], names=view.names)
