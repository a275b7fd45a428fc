"""The exception hierarchy of sosdyn: one root, a few typed branches.

Every error raised on purpose by sosdyn derives from :class:`SosdynError`, so a caller
can catch all of them at once; each message says what was wrong and what to try.
"""


class SosdynError(Exception):
    """Root of every error sosdyn raises on purpose."""


class InputError(SosdynError, ValueError):
    """Bad input caught at the boundary, before any optimisation starts."""


class PolynomialError(InputError):
    """Polynomial algebra misuse: mismatched shapes, bilinear products, bad degrees."""


class NotSymmetricError(PolynomialError):
    """A matrix that must be symmetric (SOS matrix, metric) is not."""


class DemonstrationError(InputError):
    """Demonstrations that cannot be learned from (NaN, ragged, too short, goals disagree)."""


class ResourceLimitError(InputError):
    """A request whose estimated size (bytes, steps, Gram entries) is over a limit.

    Raised before the work starts; the limit is raised with :func:`sosdyn.limits.set_limits`
    (or the ``limits`` context manager), or for the ``sosdyn`` command with the environment variable
    ``SOSDYN_<NAME>`` (:func:`sosdyn.limits.env_name`), when the machine can afford it.
    """


class ModelFileError(SosdynError):
    """A saved model that is corrupt, truncated, from another version, or was edited."""


class SolverError(SosdynError):
    """A conic solve did not produce a usable answer.

    ``status`` is the normalised status ("infeasible", "unbounded", "solver_error",
    "optimal_inaccurate"); ``hint`` says what to try next.
    """

    def __init__(self, message, status="solver_error", hint=None):
        self.status = status
        self.hint = hint
        self.detail = message
        text = message if hint is None else f"{message} Try: {hint}"
        super().__init__(text)


class UnverifiedSolutionError(SolverError):
    """The solver reported an answer whose certificate fails the independent check.

    ``report`` is the :class:`~sosdyn.sos.verification.VerificationReport` naming the failing
    block(s) and by how much.
    """

    def __init__(self, message, status="unverified", hint=None, report=None):
        self.report = report
        super().__init__(message, status, hint)


class InfeasibleError(SolverError):
    """The solver proved the program infeasible (no certificate exists at this degree)."""


class UnboundedError(SolverError):
    """The solver proved the objective unbounded (dual infeasible): no finite optimum exists."""


class NoAtomsError(SolverError):
    """No minimisers can be read from a solution's moments (not flat, or the points fail the check).

    The bound itself may still be right; only the points are refused.
    """


class WorkLimitError(SolverError):
    """An integration stopped by its work limit (``max_rollout_calls`` field calls or
    ``max_rollout_seconds`` in :mod:`sosdyn.limits`), saying how far it got: ``t`` the time reached,
    ``x`` the state there, ``calls`` and ``seconds`` the work done."""

    def __init__(self, message, hint=None, *, t=None, x=None, calls=0, seconds=0.0):
        self.t, self.x, self.calls, self.seconds = t, x, calls, seconds
        super().__init__(message, "solver_error", hint)


class NotCertifiedError(SolverError):
    """A learned model whose independent check of the certificate failed."""


class NotFittedError(SosdynError, AttributeError):
    """An estimator used before ``fit``."""
