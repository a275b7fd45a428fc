"""The convex steps of the CDSP learner (design card: alternating convex steps), one per module.

The learning problem (18)-(20) is bilinear in the fields f_k and the metric M. Each step
fixes enough to make it convex and is compiled once (:mod:`.common`):

* :class:`DynamicsStep` -- M fixed: least squares for the field coefficients subject to
  -G_k(z) - delta g(z) I being SOS matrices (k = 1..K);
* :class:`MetricStep`   -- fields fixed: maximise the margin t with -G_k - t g(z) I SOS,
  M - eps I SOS, trace M(0) = n;
* :class:`ICAStep`      -- constant metric P and the fields' linear part together: an inner
  convex approximation of the BMI that keeps every iterate certified.

g(z) = (1 + |z|^2)^(d/2) is the margin's growth (:func:`~sosdyn.lfd.fit.contraction.margin_matrix`).
"""
from .common import LeastSquaresData, TermTable, solve_with_fallback
from .dynamics import DynamicsStep
from .ica import ICAStep
from .metric import MetricStep

__all__ = ["DynamicsStep", "ICAStep", "LeastSquaresData", "MetricStep", "TermTable", "solve_with_fallback"]
