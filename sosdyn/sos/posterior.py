"""A lower bound that is a bound in floating point: the posterior correction of gamma.

A verified solution of "maximize gamma s.t. f - gamma = sigma_0 + sum_i sigma_i g_i" holds the
identity only up to a residual, and sigma_0 = z^T Q z only up to Q's tiny negative
eigenvalues. Both are multiplied by the size of the monomials where f is small: at
x = -180, |z(x)|^2 = 1 + x^2 + x^4 ~ 1e9, so lambda_min(Q) = -4e-6 moves the bound by ~4e3.
:func:`safe_shift` lowers gamma by delta until the identity is exact with a PSD matrix
(Loefberg 2009, "Pre- and post-processing sum-of-squares programs in practice"):

1. each multiplier sigma_i = z_i^T Q_i z_i is replaced by sigma_i + mu_i |z_i|^2 with
   mu_i = max(0, -lambda_min(Q_i)) + its eigenvalue error, so Q_i + mu_i I >= 0; the
   change, - sum_i mu_i |z_i|^2 g_i, joins the residual
   e = f - gamma - sum_i sigma_i g_i - z^T Q z (all at the solver's numbers);
2. e (every monomial of it a product z_j z_k) is absorbed into Q: E_jk = e_a / n_a for the
   n_a pairs with z_j z_k = x^a, so f - gamma = z^T (Q + E) z + sum_i sigma_i' g_i + rho,
   rho the rounding error of the sums, |rho_a| <= r (a bound from the magnitudes summed);
3. with A = Q + E and z_0 = 1, delta >= 0 is the smallest with lambda_min(A + delta e_0 e_0^T)
   >= tau, tau = sum_a r + the eigenvalue error of A (Schur complement on the other rows).

Then for every x in K: f(x) - (gamma - delta) = z^T (A + delta e_0 e_0^T) z + sum sigma_i' g_i
+ rho(x) >= tau |z|^2 - sum_a |rho_a| |x^a| >= 0, because every x^a = z_j z_k has |x^a| <=
(z_j^2 + z_k^2) / 2 <= |z|^2 -- on R^n too, with no bound on x. So gamma - delta (rounded
down) is <= min_K f. On a set K with |x_i| <= R_i (:func:`~.sets.variable_bounds`: boxes, balls, polytopes)
a second delta also holds: f - gamma >= (lambda_min(A) - tau) |z|^2 - sum_{a off z z^T} |e_a|
|x^a| on K, so delta_K = max(0, tau - lambda_min(A)) sup_K |z|^2 + sum |e_a| R^a suffices
(sup_K |z|^2 <= sum_j R^{2 z_j}); the smaller of the two is used. K is read from the
constraint itself (the constraints of its multipliers, :func:`constraint_set`).

:func:`safe_point` applies this to any program of the form "maximize c t s.t. t enters
one SOS constraint only as -a t in its constant term" (:func:`bound_pattern`): t lowered by
delta / a is what ``Solution.objective`` and ``Solution.value(t)`` return for it --
``minimize_on`` and hand-written bound programs alike. When neither exists (A's
negative direction avoids the constant, or e has a monomial outside z z^T, on an unbounded
set), no number is returned: UnverifiedSolutionError.
"""
from __future__ import annotations

import numpy as np

from ..errors import UnverifiedSolutionError
from ..poly import Polynomial
from .conic import objective_value, positions
from .gram import svec_to_matrix
from .objective import affine_rows
from .sets import BasicSet, variable_bounds
from .verification import fp_error, gram_structure

EPS = np.finfo(float).eps
FACES = (1e-9, 1e-7, 1e-5)     # relative Gram diagonals below which a row is off the face (face_masks)
_HINT = "rescale the variables so the minimiser is near the unit box, or a set K that bounds the variables"


def constant_need(A, k0: int, tau: float) -> float:
    """The signed number c with lambda_min(A + d e_k0 e_k0^T) >= tau iff d >= c (up to rounding),
    or inf when no d works. With A' = A without row/column k0 and b = A[others, k0]: PSD iff
    A' - tau I > 0 and a_00 + d - tau >= b^T (A' - tau I)^{-1} b (Schur complement)."""
    rest = np.delete(np.arange(A.shape[0]), k0)
    Ar = A[np.ix_(rest, rest)] - tau * np.eye(rest.size)
    if rest.size and np.linalg.eigvalsh(Ar)[0] <= fp_error(A):
        return np.inf
    b = A[rest, k0]
    return tau - A[k0, k0] + (float(b @ np.linalg.solve(Ar, b)) if rest.size else 0.0)


def constant_shift(A, k0: int, tau: float, need: float | None = None) -> float:
    """Smallest delta >= 0 with lambda_min(A + delta e_k0 e_k0^T) >= tau (checked), or inf."""
    need = constant_need(A, k0, tau) if need is None else need
    if not np.isfinite(need):
        return np.inf
    delta = max(0.0, need)
    step = tau + 1e-12 * (delta + abs(A[k0, k0]))
    for _ in range(64):                    # the solve's own rounding: confirm, grow if needed
        B = A.copy()
        B[k0, k0] += delta
        if np.linalg.eigvalsh(B)[0] >= tau:
            return delta
        delta, step = delta + step, 2.0 * step
    return np.inf


def shared_constant(As, zeros, taus) -> float:
    """delta = sum_k c_k with every lambda_min(A_k + c_k e_0 e_0^T) >= tau_k (checked): the blocks
    share the constant monomial, so a block with room (c_k < 0: its Schur complement exceeds
    tau_k) gives up to half of it to the blocks that need a raise; inf if a block cannot be
    made PSD by its constant."""
    needs = [constant_need(A, k0, tau) for A, k0, tau in zip(As, zeros, taus)]
    if not all(np.isfinite(needs)):
        return np.inf
    raise_ = sum(constant_shift(A, k0, tau, c) for A, k0, tau, c in zip(As, zeros, taus, needs) if c > 0)
    room = -sum(c for c in needs if c < 0)
    take = min(raise_, room / 2)
    given = 0.0
    for A, k0, tau, c in zip(As, zeros, taus, needs):
        if c < 0 and take > 0:
            low = take * (-c) / room
            B = A.copy()
            B[k0, k0] -= low
            given += low if np.linalg.eigvalsh(B)[0] >= tau else 0.0
    return max(0.0, raise_ - given) + 1e-12 * raise_


def multiplier_shift(con, at):
    """(- sum_i mu_i |z_i|^2 g_i, sum of |coefficients| summed) for the multipliers of ``con``
    with lambda_min(Q_i) below their eigenvalue error (step 1 of the module docstring)."""
    vars = con.basis.vars
    adj, mag = Polynomial.constant(0.0).with_vars(vars), 0.0
    for m in con.multipliers:
        Q = svec_to_matrix(at(m.psd.ids), m.psd.size)
        if not Q.size:
            continue
        mu = max(0.0, -float(np.linalg.eigvalsh(Q)[0])) + fp_error(Q)
        if mu > 0:
            square = Polynomial(m.basis.vars, 2 * m.basis.exps, np.ones(len(m.basis)))
            term = (mu * square * m.constraint).with_vars(vars)
            adj, mag = adj - term, mag + float(np.abs(term.coef).sum())
    return adj, mag


def compact_shift(A, tau, basis_exps, off_exps, off_coef, R) -> float:
    """delta_K of the module docstring for |x_i| <= R_i (inf without R)."""
    if R is None:
        return np.inf
    lam = float(np.linalg.eigvalsh(A)[0]) if A.size else 0.0
    sup_z = float(np.prod(R ** (2 * basis_exps), axis=1).sum())
    off = float((np.abs(off_coef) * np.prod(R ** off_exps, axis=1)).sum()) if off_coef.size else 0.0
    return (max(0.0, tau - lam) * sup_z + off) * (1 + 1e-12)


def safe_shift(solution, con) -> float:
    """delta >= 0 such that raising the constant term of ``con``'s polynomial by delta makes its
    certificate hold exactly with a PSD Gram matrix (module docstring), on the set of ``con``'s
    multipliers (:func:`constraint_set`). Raises UnverifiedSolutionError when no safe shift
    exists."""
    ids, x = solution.data.ids, solution.x
    at = lambda block_ids: x[positions(ids, block_ids)]  # noqa: E731
    if hasattr(con, "identity_values"):                   # several Gram blocks (correlative sparsity)
        return _checked(block_shift(con, at), con)
    vars = con.basis.vars
    p = con.poly.with_vars(vars)
    coef = p.coef[:, 0] + p.coef[:, 1:] @ at(p.ids)
    mag = float(np.abs(p.coef[:, 0]).sum() + (np.abs(p.coef[:, 1:]) @ np.abs(at(p.ids))).sum())
    adj, adj_mag = multiplier_shift(con, at)
    r = Polynomial(vars, p.exps, coef) + adj
    if not r.exps.shape[0]:
        r = Polynomial(vars, np.zeros((1, len(vars)), dtype=np.int64), [0.0])
    Q = svec_to_matrix(at(con.psd.ids), con.psd.size)
    st = gram_structure(r.exps, con.basis.exps)
    rounding = (p.coef.shape[1] + Q.size + 8) * EPS * (mag + adj_mag + float(np.abs(Q).sum()))
    K = constraint_set(con)
    R = variable_bounds(K, vars) if K.ineqs or K.eqs else None
    U = _union_exps(r.exps, con.basis.exps, st) if R is not None else None
    compact = None if R is None else lambda A, kept, off, e: compact_shift(  # noqa: E731
        A, rounding + fp_error(A), con.basis.exps[kept], U[off], e[off], R)
    at_one = np.zeros(st.in_gram.size)                   # the whole rounding bound on the constant
    zero = np.flatnonzero(~con.basis.exps.any(axis=1))   # (always kept): one block, tau = rounding
    if zero.size:
        at_one[st.pair_at[zero[0] * (Q.shape[0] + 1)]] = rounding
    return _checked(face_shift(r.coef[:, 0], st, [Q], [con.basis.exps], at_one, compact), con)


def face_masks(Qs, zeros):
    """Kept-row masks of every block, one list per face tried: the whole basis, then the rows
    whose diagonal exceeds rel x the block's largest (rel in FACES), the constant monomial (row
    ``zeros[k]``) always kept -- the face the solver's point lies on (monomials whose square p
    cannot produce have a zero diagonal in every exact certificate, and a negative eigenvalue
    there would multiply an unbounded |z_j|^2)."""
    yield [np.ones(Q.shape[0], dtype=bool) for Q in Qs]
    for rel in FACES:
        masks = [np.diag(Q) > rel * float(np.diag(Q).max(initial=0.0)) for Q in Qs]
        for m, z in zip(masks, zeros):
            m[z] = True
        yield masks


def face_shift(p_coef, st, Qs, basis_exps, r, compact=None) -> float:
    """min over the faces of :func:`face_masks` of sum_k delta_k (module docstring, steps 2-3) for
    p - gamma = sum_k z_k^T Q_k z_k + e over the blocks Qs: rows off the face are set to zero
    (their products join the residual e), e_a is split over the kept pairs of the first block
    with a kept pair producing x^a, and delta_k is the smallest with lambda_min(A_k + delta_k
    e_0 e_0^T) >= tau_k on block k's kept rows (:func:`shared_constant`), tau_k = the rounding
    bounds ``r`` (|rho_a| <= r_a) of the monomials block k owns + its eigenvalue error: each owned
    |x^a| <= |z_k|^2, so sum_k tau_k |z_k|^2 >= sum_a |rho_a| |x^a|.
    A residual monomial no kept pair produces leaves only ``compact(A, kept, off, e)`` (one
    block; inf without). Every face gives an exact identity, so each delta is safe; the
    smallest is returned."""
    sizes = np.array([Q.shape[0] for Q in Qs], dtype=np.int64)
    owner = np.repeat(np.arange(len(Qs)), sizes ** 2)
    size = st.in_gram.size
    base = np.bincount(st.p_at, weights=p_coef, minlength=size)
    best = np.inf
    zeros = [np.flatnonzero(~B.any(axis=1))[:1] for B in basis_exps]
    for kept in face_masks(Qs, zeros):
        pair_kept = np.concatenate([np.outer(k, k).ravel() for k in kept])
        vals = np.concatenate([Q.ravel() for Q in Qs])
        e = base - np.bincount(st.pair_at, weights=np.where(pair_kept, vals, 0.0), minlength=size)
        first = np.full(size, len(Qs), dtype=np.int64)
        np.minimum.at(first, st.pair_at[pair_kept], owner[pair_kept])
        own = pair_kept & (owner == first[st.pair_at])
        n = np.bincount(st.pair_at[own], minlength=size)
        E = np.where(own, e[st.pair_at] / np.maximum(n[st.pair_at], 1), 0.0)
        off = (e != 0.0) & (n == 0)
        starts = np.cumsum(np.concatenate([[0], sizes ** 2]))
        As = [(Q + E[s0:s0 + Q.size].reshape(Q.shape))[np.ix_(k, k)] for Q, k, s0 in zip(Qs, kept, starts)]
        at = [np.flatnonzero(~B[k].any(axis=1))[:1] for k, B in zip(kept, basis_exps)]   # z_0 in the kept rows
        owned = np.bincount(first, weights=r, minlength=len(Qs) + 1)
        delta = np.inf if off.any() or not all(z.size for z in at) else shared_constant(
            As, [int(z[0]) for z in at], [owned[k] + fp_error(A) for k, A in enumerate(As)])
        A = As[0]
        if compact is not None:
            delta = min(delta, compact(A, kept[0], off, e))
        best = min(best, delta)
    return best


def _checked(delta: float, con) -> float:
    if not np.isfinite(delta):
        raise UnverifiedSolutionError(
            f"the bound of {con.name!r} cannot be made safe: its Gram matrix has a negative "
            "direction that lowering gamma does not reach, or its residual a monomial no Gram "
            "product produces, and the set bounds no variable box", "unverified", _HINT)
    return float(delta)


def block_shift(con, at) -> float:
    """:func:`safe_shift` for p - gamma = sum_k z_k^T Q_k z_k over several Gram blocks (each
    clique's basis holds 1; :func:`face_shift`): the rounding of monomial a is bounded by
    r_a = (terms summed + 8) eps sum |terms| (p's, then the products z_j z_k Q_jk giving x^a),
    each block's tau from the monomials it owns. Only for plain SOS (no Putinar multipliers:
    inf, so the caller refuses)."""
    if any(m.psd.role != "clique" for m in con.multipliers) or con.eq_multipliers:
        return np.inf
    coef, st, Qs, _ = con.identity_values(at)
    p = con.p
    size = st.in_gram.size
    mag = np.bincount(st.p_at, weights=np.abs(p.coef[:, 0]) + np.abs(p.coef[:, 1:]) @ np.abs(at(p.ids)),
                      minlength=size) + np.bincount(st.pair_at, weights=np.abs(np.concatenate(
                          [Q.ravel() for Q in Qs])), minlength=size)
    terms = p.coef.shape[1] + int(np.bincount(st.pair_at, minlength=size).max(initial=0)) + 8
    return face_shift(coef, st, Qs, [basis.exps for basis, _ in con.gram_blocks], terms * EPS * mag)


def constraint_set(con) -> BasicSet:
    """The set K on which ``con`` shows its polynomial nonnegative: the constraints of its
    multipliers (g_i >= 0, products included; sparse clique blocks are multipliers of 1, not
    constraints) and of its free multipliers (h_j = 0). R^n for add_sos."""
    return BasicSet(ineqs=[m.constraint for m in con.multipliers if m.psd.role != "clique"],
                    eqs=[m.constraint for m in con.eq_multipliers])


def bound_pattern(program):
    """(con, t, c, a) when ``program`` maximises c t + c0 (c > 0) for one decision t that enters
    the program only as -a t (a > 0) in the constant term of one SOS constraint ``con``
    (f - gamma SOS, f - gamma >= 0 on K): its optimum is a lower bound; else None."""
    sense, expr = program.objective or (None, None)
    if sense != "max" or not isinstance(expr, Polynomial) or program.cvxpy_constraints:
        return None
    _, C, expr_ids = affine_rows([expr])
    nz = np.flatnonzero(C[0])
    if nz.size != 1 or C[0, nz[0]] <= 0:
        return None
    t = int(expr_ids[nz[0]])
    if any(t in set(rows.ids.tolist()) for rows in program.linear if rows.role == "user"):
        return None
    hits = []
    for con in program.sos_constraints:
        poly = con.p if hasattr(con, "identity_values") else con.poly   # sparse: p, not p - sum sigma_k
        col = np.flatnonzero(poly.ids == t)
        if not col.size:
            continue
        coefs = poly.coef[:, 1 + col[0]]
        rows = np.flatnonzero(coefs)
        if rows.size != 1 or poly.exps[rows[0]].any() or coefs[rows[0]] >= 0:
            return None
        hits.append((con, -float(coefs[rows[0]])))
    if len(hits) != 1:
        return None
    return hits[0][0], t, float(C[0, nz[0]]), hits[0][1]


def safe_point(solution, found) -> tuple[int, float, float]:
    """(position of t in the solution's decision vector, t - delta / a, c (t - delta / a) + c0),
    both rounded down, for a lower-bound program ``found`` = :func:`bound_pattern` (c, c0 of its
    objective c t + c0): the certificate holds exactly at the lowered t, so both are safe.
    Raises UnverifiedSolutionError when no safe shift exists."""
    con, t, c, a = found
    pos = int(positions(solution.data.ids, np.array([t], dtype=np.int64))[0])
    value = objective_value(solution.data, solution.x)
    shift = safe_shift(solution, con) / a
    t_now = float(solution.x[pos])
    low_t, low = t_now - shift, value - c * shift
    return (pos, float(np.nextafter(low_t - 4 * EPS * (abs(t_now) + abs(low_t)), -np.inf)),
            float(np.nextafter(low - 4 * EPS * (abs(value) + abs(low)), -np.inf)))


def _union_exps(p_exps, basis_exps, st) -> np.ndarray:
    """The exponent rows of the union U of ``st`` (p's monomials and the Gram products)."""
    B = basis_exps
    pairs = (B[:, None, :] + B[None, :, :]).reshape(-1, B.shape[1])
    U = np.zeros((st.in_gram.size, B.shape[1]), dtype=np.int64)
    U[st.p_at], U[st.pair_at] = p_exps, pairs
    return U
