"""Moments: the dual side of an SOS constraint, and minimisers read from it.

For an SOS constraint "p - sum_i sigma_i g_i = z(x)^T Q z(x), Q >= 0" with basis
z = (x^b_1, ..., x^b_N), the solver's dual of the PSD cone Q >= 0 is a PSD matrix S with
S_ij = y_{b_i + b_j}: the *moment matrix* M(y) of a linear functional L(x^alpha) = y_alpha on
polynomials (a pseudo-expectation). For "maximise gamma with p - gamma SOS" it is Lasserre's
moment relaxation: minimise L(p) subject to L(1) = 1 and M(y) >= 0. :class:`Moments` holds y,
normalised so that y_0 = L(1) = 1 when the basis holds the monomial 1 (else, or when y_0
is below tol * max|S|, so that trace(M) = 1).

Read as numbers only after two checks (:func:`moments_from_dual`): M is PSD (smallest
eigenvalue >= -tol * max|M|) and M is a moment matrix (entries with equal b_i + b_j agree to
tol * max|M|); otherwise :class:`~sosdyn.errors.UnverifiedSolutionError`.

Atoms (Henrion & Lasserre 2005, as in GloptiPoly): when M is *flat*, rank M(B) = rank M(B')
with B' the basis monomials of degree <= t - shift (t the basis degree), L is the integral
against r = rank M points x_j with weights w_j > 0: M = sum_j w_j z(x_j) z(x_j)^T.
:func:`extract_atoms` finds them: M = V V^T (eigenvalues above rank_tol * lambda_max), V in
column echelon form U (U[w] = I on r pivot monomials w, so z(x) = U w(x) on the support),
multiplication matrices N_i = U[x_i w] (x_i w(x_j) = N_i w(x_j)), a random combination
N = sum c_i N_i and its ordered real Schur form N = Q T Q^T: x_j[i] = q_j^T N_i q_j. Weights
are the least-squares solution of M = sum_j w_j z(x_j) z(x_j)^T, and the atoms are returned
only if that residual is below tol * max|M| and every w_j > 0. Not flat, complex
eigenvalues, a missing product x_i w or a residual above tol: :class:`~sosdyn.errors.NoAtomsError`,
never invented points.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from ..errors import InputError, NoAtomsError, UnverifiedSolutionError
from ..poly import Polynomial, unique_rows
from .gram import svec_pairs

MOMENT_HINT = ("tighter solver tolerances (Clarabel: tol_feas=1e-10, tol_gap_abs=1e-10, tol_gap_rel=1e-10) "
               "or backend='direct' (Clarabel's own duals)")


@dataclass
class Atoms:
    """Points x_j (rows of ``points``, columns in ``vars`` order) and weights w_j > 0.

    ``residual`` is max|M - sum_j w_j z(x_j) z(x_j)^T| / max|M|; ``rank`` the numerical rank of M.
    ``Solution.minimizers`` sets ``solver_value`` (the relaxation's value the points attain) and,
    beside it, ``bound`` (the proven safe bound; nan when none was proven).
    """

    vars: tuple
    points: np.ndarray
    weights: np.ndarray
    rank: int
    residual: float
    solver_value: float = float("nan")
    bound: float = float("nan")

    def __len__(self) -> int:
        return self.points.shape[0]


class Moments:
    """Pseudo-moments y_alpha of one SOS constraint (see module doc): M_ij = y_{b_i + b_j}."""

    def __init__(self, vars, basis: np.ndarray, matrix: np.ndarray, exps: np.ndarray, values: np.ndarray):
        self.vars, self.basis, self.matrix = tuple(vars), basis, matrix
        self.exps, self.values = exps, values

    def moment(self, alpha) -> float:
        """y_alpha for an exponent tuple in ``vars`` order; InputError if it is not in M."""
        a = np.asarray(alpha)
        if a.ndim != 1 or a.size != len(self.vars) or not np.issubdtype(a.dtype, np.integer) or (a < 0).any():
            raise InputError(f"moment() takes one exponent per variable of {self.vars} (non-negative "
                             f"integers), got {alpha!r}. Try: a tuple of length {len(self.vars)}")
        alpha = a.astype(np.int64).reshape(1, -1)
        hit = np.flatnonzero((self.exps == alpha).all(axis=1))
        if not hit.size:
            raise InputError(f"the moment of {_monomial(self.vars, alpha[0])} is not an entry of this "
                             "moment matrix (degree above twice the Gram basis degree). Try: a polynomial "
                             "whose monomials are products of two basis monomials")
        return float(self.values[hit[0]])

    def expectation(self, p: Polynomial) -> float:
        """L(p) = sum_alpha p_alpha y_alpha for a numeric polynomial p (variables by name)."""
        if not isinstance(p, Polynomial) or not p.is_numeric:
            raise InputError("expectation() takes a numeric Polynomial. Try: sol.value(poly) first")
        extra = [v for v in p.vars if v not in self.vars and p.degree_in(v) > 0]
        if extra:
            raise InputError(f"variables {extra} are not variables of these moments {self.vars}")
        q = p.with_vars(self.vars + tuple(v for v in p.vars if v not in self.vars))
        return float(sum(c * self.moment(e[:len(self.vars)]) for e, c in zip(q.exps, q.coef[:, 0])))

    def rank(self, rank_tol: float = 1e-6) -> int:
        """Numerical rank: eigenvalues above rank_tol * lambda_max."""
        return _rank(self.matrix, rank_tol)

    def atoms(self, rank_tol: float = 1e-6, tol: float = 1e-6, shift: int = 1, seed: int = 0) -> Atoms:
        """The atoms of a flat moment matrix (:func:`extract_atoms`)."""
        return extract_atoms(self.vars, self.basis, self.matrix, rank_tol, tol, shift, seed)

    def __repr__(self) -> str:
        return f"Moments({len(self.basis)} x {len(self.basis)} over {self.vars}, rank {self.rank()})"


def _monomial(vars, alpha) -> str:
    return "*".join(v if e == 1 else f"{v}^{e}" for v, e in zip(vars, alpha) if e) or "1"


def _rank(M: np.ndarray, rank_tol: float) -> int:
    ev = np.linalg.eigvalsh(M)
    return int((ev > rank_tol * max(ev.max(initial=0.0), 1e-300)).sum())


def moments_from_dual(vars, basis: np.ndarray, S: np.ndarray, tol: float = 1e-6) -> Moments:
    """Check a PSD-cone dual S and normalise it into :class:`Moments` (module doc).

    Raises UnverifiedSolutionError if S is not PSD or not a moment matrix to ``tol``, or is zero.
    """
    S = 0.5 * (S + S.T)
    scale = np.abs(S).max(initial=0.0)
    if not np.isfinite(S).all() or scale == 0.0:
        raise UnverifiedSolutionError("the dual of this constraint is zero or not finite, so it carries "
                                      "no moments (a feasibility program without an objective has none)",
                                      "unverified", "maximise a bound (e.g. gamma with p - gamma SOS)")
    lam = float(np.linalg.eigvalsh(S)[0])
    if lam < -tol * scale:
        raise UnverifiedSolutionError(f"the dual moment matrix is not PSD: smallest eigenvalue {lam:.3g} "
                                      f"(max entry {scale:.3g})", "unverified", MOMENT_HINT)
    zero = np.flatnonzero((basis == 0).all(axis=1))
    norm = S[zero[0], zero[0]] if zero.size and S[zero[0], zero[0]] > tol * scale else np.trace(S)
    M = S / norm
    i, j = svec_pairs(len(basis))
    exps, which = unique_rows(basis[i] + basis[j])      # the monomial b_i + b_j of each pair
    values = np.zeros(exps.shape[0])
    np.add.at(values, which, M[i, j])
    values /= np.bincount(which, minlength=exps.shape[0])
    spread = np.abs(M[i, j] - values[which]).max(initial=0.0)
    if spread > tol * np.abs(M).max():
        raise UnverifiedSolutionError(f"the dual is not a moment matrix: entries for the same monomial "
                                      f"differ from their mean by {spread:.3g} (max entry {np.abs(M).max():.3g})",
                                      "unverified", MOMENT_HINT)
    return Moments(vars, basis, M, exps, values)


def _column_echelon(V: np.ndarray, tol: float):
    """U with U[pivots] = I spanning the columns of V (row pivots taken in basis order)."""
    R = V.T.copy()                       # r x N, rows reduced to RREF
    r, N = R.shape
    pivots, row = [], 0
    for col in range(N):
        if row == r:
            break
        k = row + int(np.argmax(np.abs(R[row:, col])))
        if abs(R[k, col]) <= tol:
            continue
        R[[row, k]] = R[[k, row]]
        R[row] /= R[row, col]
        others = np.arange(r) != row
        R[others] -= np.outer(R[others, col], R[row])
        pivots.append(col)
        row += 1
    if row < r:
        return None, pivots
    return R.T, pivots


def extract_atoms(vars, basis: np.ndarray, M: np.ndarray, rank_tol: float = 1e-6, tol: float = 1e-6,
                  shift: int = 1, seed: int = 0) -> Atoms:
    """Points and weights with M = sum_j w_j z(x_j) z(x_j)^T, by flat extension (module doc).

    ``shift``: the flatness test compares rank M(B) with rank M(B') on the basis monomials of
    degree <= t - shift (use d_g = max ceil(deg g_i / 2) for constraints g_i >= 0).
    """
    deg = basis.sum(axis=1)
    t = int(deg.max(initial=0))
    low = deg <= t - shift
    r = _rank(M, rank_tol)
    r_low = _rank(M[np.ix_(low, low)], rank_tol) if low.any() else 0
    if r != r_low:
        raise NoAtomsError(f"the moment matrix is not flat: rank {r} on the basis of degree <= {t}, "
                           f"{r_low} on degree <= {t - shift}, so it is not known to come from finitely "
                           "many points and none are returned", "no_atoms",
                           "a higher degree (the relaxation may not be tight yet, or the minimisers "
                           "are not finitely many)")
    ev, vec = np.linalg.eigh(M)
    keep = ev > rank_tol * ev.max()
    V = vec[:, keep] * np.sqrt(ev[keep])
    U, pivots = _column_echelon(V, rank_tol * np.abs(V).max())
    if U is None:
        raise NoAtomsError("no column echelon form of the moment matrix's factor", "no_atoms",
                           "a larger rank_tol")
    n = basis.shape[1]
    index = {tuple(b): k for k, b in enumerate(basis)}
    N = []
    for i in range(n):
        rows = []
        for p in pivots:
            target = basis[p].copy()
            target[i] += 1
            if tuple(target) not in index:
                raise NoAtomsError(f"{vars[i]} * {_monomial(vars, basis[p])} is not in the Gram basis, "
                                   "so no multiplication matrix can be formed", "no_atoms",
                                   "the full basis of all monomials up to the degree (basis=...)")
            rows.append(U[index[tuple(target)]])
        N.append(np.array(rows))
    c = np.random.default_rng(seed).random(n)
    c /= c.sum()
    T, Q = sla.schur(sum(ci * Ni for ci, Ni in zip(c, N)), output="real")
    if r > 1 and np.abs(np.diag(T, -1)).max() > tol * max(np.abs(T).max(), 1.0):
        raise NoAtomsError("the multiplication matrices have complex eigenvalues: no real atoms",
                           "no_atoms", "a higher degree")
    points = np.array([[Q[:, j] @ Ni @ Q[:, j] for Ni in N] for j in range(r)])
    Z = np.prod(points[:, None, :] ** basis[None, :, :], axis=2)        # z(x_j), r x N
    A = np.stack([np.outer(z, z).ravel() for z in Z], axis=1)
    w = np.linalg.lstsq(A, M.ravel(), rcond=None)[0]
    residual = float(np.abs(A @ w - M.ravel()).max() / np.abs(M).max())
    if residual > tol or (w <= 0).any():
        raise NoAtomsError(f"the {r} candidate points do not reproduce the moment matrix (relative residual "
                           f"{residual:.2g}, weights {np.round(w, 6).tolist()})", "no_atoms",
                           "a higher degree, or a larger tol if the solver's accuracy is the limit")
    return Atoms(tuple(vars), points, w, r, residual)


def check_atoms(atoms: Atoms, residual: Polynomial, ineqs=(), eqs=(), tol: float = 1e-6,
                bound_error=None) -> None:
    """Check that every atom attains the bound: residual(x_j) = 0, g(x_j) >= 0, h(x_j) = 0.

    ``residual`` is the certified polynomial at the solution (p - gamma: zero exactly where p
    attains the bound gamma); the constraints are tested to ``tol`` times (1 + the polynomial's
    largest coefficient), the residual to the bound's own error at each point,
    ``bound_error(points, vars)`` (default: the same as the constraints) -- a local minimiser higher
    than that is no minimiser. NoAtomsError names the first point and polynomial that fail.
    """
    def scale(p):
        return tol * (1.0 + np.abs(p.coef[:, 0]).max(initial=0.0))

    attain = scale(residual) if bound_error is None else bound_error(atoms.points, atoms.vars)
    tests = [(residual, "attains the bound (p - bound = 0)", lambda v, s: np.abs(v) <= attain)]
    tests += [(g, f"satisfies {g!r} >= 0", lambda v, s: v >= -s) for g in ineqs]
    tests += [(h, f"satisfies {h!r} = 0", lambda v, s: np.abs(v) <= s) for h in eqs]
    for p, what, ok in tests:
        values = p(atoms.points, atoms.vars)
        bad = np.flatnonzero(~ok(values, scale(p)))
        if bad.size:
            j = int(bad[0])
            raise NoAtomsError(f"extracted point {np.round(atoms.points[j], 8).tolist()} (over {atoms.vars}) "
                               f"fails the check: it should satisfy that it {what}, value {values[j]:.3g}",
                               "no_atoms", "a higher degree, or tighter solver tolerances")
