"""Basic semialgebraic sets K = {x : g_i(x) >= 0, h_j(x) = 0} and their Putinar terms.

``add_nonneg_on(p, K, degree)`` certifies p >= 0 on K by (Putinar 1993; the S-procedure when
every multiplier is a constant)

    p = sigma_0 + sum_S sigma_S g_S + sum_j lambda_j h_j,   sigma SOS, lambda free,

where S runs over the single inequalities and, with ``products``, over products
g_S = prod_{i in S} g_i of up to ``products`` of them (Schmuedgen's preorder: products can
certify at a lower degree what single terms need a higher degree for). Each multiplier has
the largest degree with deg(multiplier * constraint) <= its degree bound: ``degree`` as one
int for all, or a list/dict giving the bound per constraint (index into ineqs + eqs).

:class:`BasicSet` holds the constraints; :func:`putinar_terms` lists (constraint, its SOS or
free multiplier's degree) for a relaxation degree.
"""
from __future__ import annotations

import math
from fractions import Fraction
from itertools import combinations, product

import numpy as np
from scipy.optimize import linprog

from ..errors import InputError, PolynomialError
from ..poly import MAX_COEFFICIENT, Polynomial, variables


def _set_variables(vars, what) -> list:
    """Variables of a box/ball: a string of names or a sequence of single variables."""
    xs = variables(vars) if isinstance(vars, str) else list(vars) if isinstance(vars, (list, tuple)) else None
    if not xs or not all(isinstance(v, Polynomial) and v.is_numeric and v.degree == 1 and len(v.vars) == 1
                         and v.coef.shape[0] == 1 and v.coef[0, 0] == 1.0 for v in xs):
        raise InputError(f"BasicSet.{what} takes variables (a string of names or a list of variables), "
                         f"got {vars!r}. Try: BasicSet.{what}('x y', ...) or BasicSet.{what}([x, y], ...)")
    if len({v.vars[0] for v in xs}) < len(xs):
        raise InputError(f"BasicSet.{what}: a variable is repeated in {vars!r}. Try: each variable once")
    return xs


def _numbers(value, n: int, what) -> np.ndarray:
    """``value`` (a number or n numbers) as n finite floats (InputError otherwise)."""
    try:
        a = np.broadcast_to(np.asarray(value, dtype=float), (n,))
    except (TypeError, ValueError):
        raise InputError(f"{what} must be a number or {n} numbers, got {value!r}") from None
    if not np.isfinite(a).all():
        raise InputError(f"{what} must be finite, got {value!r}")
    return a


def _as_poly(g, what) -> Polynomial:
    if isinstance(g, (int, float)):
        g = Polynomial.constant(float(g))
    if not isinstance(g, Polynomial) or not g.is_numeric:
        raise PolynomialError(f"{what} must be a numeric Polynomial, got {g!r}. Try: x**2 + y**2 - 1")
    return g


class BasicSet:
    """K = {x : g_i(x) >= 0 for g in ``ineqs``, h_j(x) = 0 for h in ``eqs``}.

    >>> x, y = variables("x y"); K = BasicSet(ineqs=[1 - x**2 - y**2])       # the unit disk
    """

    def __init__(self, ineqs=(), eqs=()):
        for given, what in ((ineqs, "ineqs"), (eqs, "eqs")):
            if isinstance(given, (Polynomial, str, int, float)) or not hasattr(given, "__iter__"):
                raise InputError(f"BasicSet {what} is a list of polynomials, got {given!r}. Try: {what}=[g]")
        self.ineqs = tuple(_as_poly(g, f"inequality {k}") for k, g in enumerate(ineqs))
        self.eqs = tuple(_as_poly(h, f"equality {k}") for k, h in enumerate(eqs))
        names: tuple = ()
        for g in self.ineqs + self.eqs:
            names = names + tuple(v for v in g.vars if v not in names)
        self.vars = names

    @classmethod
    def box(cls, vars, lower, upper) -> BasicSet:
        """The box lower_i <= x_i <= upper_i as (x_i - lower_i)(upper_i - x_i) >= 0 per variable."""
        xs = _set_variables(vars, "box")
        lo, hi = _numbers(lower, len(xs), "lower"), _numbers(upper, len(xs), "upper")
        if (lo > hi).any():
            k = int(np.argmax(lo > hi))
            raise InputError(f"BasicSet.box: lower {float(lo[k])!r} > upper {float(hi[k])!r} for {xs[k]!r}: the box is "
                             "empty. Try: BasicSet.box(vars, lower, upper) with lower <= upper")
        return cls(ineqs=[(x - float(a)) * (float(b) - x) for x, a, b in zip(xs, lo, hi)])

    @classmethod
    def ball(cls, vars, radius=1.0, center=None) -> BasicSet:
        """The ball ||x - center|| <= radius as radius^2 - ||x - center||^2 >= 0."""
        xs = _set_variables(vars, "ball")
        r = _numbers(radius, 1, "radius")[0]
        if r < 0:
            raise InputError(f"BasicSet.ball: radius {float(r)!r} < 0: the ball is empty. Try: radius >= 0")
        c = np.zeros(len(xs)) if center is None else _numbers(center, len(xs), "center")
        if not r <= MAX_COEFFICIENT ** 0.5:
            raise InputError(f"BasicSet.ball: radius {float(r)!r} squared is above {MAX_COEFFICIENT:.0e}, the "
                             "largest coefficient a polynomial takes. Try: rescale the variables")
        return cls(ineqs=[float(r) ** 2 - sum((x - float(ci)) ** 2 for x, ci in zip(xs, c))])

    def __and__(self, other: BasicSet) -> BasicSet:
        """The intersection: both sets' constraints."""
        if not isinstance(other, BasicSet):
            raise InputError(f"& intersects two BasicSets, got {type(other).__name__}. "
                             "Try: K & BasicSet(ineqs=[g])")
        return BasicSet(self.ineqs + other.ineqs, self.eqs + other.eqs)

    def contains(self, points, tol: float = 1e-9) -> np.ndarray:
        """Boolean mask of the rows of ``points`` (columns in ``self.vars`` order) lying in K."""
        X = np.atleast_2d(np.asarray(points, dtype=float))
        ok = np.ones(X.shape[0], dtype=bool)
        for g in self.ineqs:
            ok &= g(X, self.vars) >= -tol
        for h in self.eqs:
            ok &= np.abs(h(X, self.vars)) <= tol
        return ok

    def __repr__(self) -> str:
        parts = [f"{g!r} >= 0" for g in self.ineqs] + [f"{h!r} = 0" for h in self.eqs]
        return "BasicSet{" + ", ".join(parts) + "}"


def variable_box(K: BasicSet, vars) -> tuple[np.ndarray, np.ndarray] | None:
    """(lo, hi) with lo_i <= x_i <= hi_i on K for each of ``vars``, or None when some x_i is not
    bounded by what is read here: separable quadratics c + l.x - sum_i a_i x_i^2 >= 0 (a_i > 0:
    boxes, balls, ellipses; |x_i - m_i| <= ((c + sum l_i^2 / 4 a_i) / a_i)^(1/2)) and the polytope
    of the linear inequalities (an LP per variable and side); the intervals are intersected."""
    lo, hi = np.full(len(vars), -np.inf), np.full(len(vars), np.inf)
    at = {v: i for i, v in enumerate(vars)}
    lin = []
    for g in K.ineqs:
        if any(v not in at for v in g.vars) or g.degree > 2:
            continue
        cols = [at[v] for v in g.vars]
        E, c = g.exps, g.coef[:, 0]
        if g.degree == 1:
            row = np.zeros(len(vars) + 1)
            for e, a in zip(E, c):
                row[-1 if not e.any() else cols[int(np.argmax(e))]] += a
            lin.append(row)
            continue
        if (E.sum(axis=1) == 2).any() and (E[E.sum(axis=1) == 2].max(axis=1) < 2).any():
            continue                                          # a cross term x_i x_j
        quad, line, c0 = {}, {}, float(c[~E.any(axis=1)].sum())
        for e, a in zip(E, c):
            if e.sum() == 2:
                quad[int(np.argmax(e))] = a
            elif e.sum() == 1:
                line[int(np.argmax(e))] = a
        if not quad or any(a >= 0 for a in quad.values()) or set(line) - set(quad):
            continue
        rhs = c0 + sum(line.get(k, 0.0) ** 2 / (-4 * a) for k, a in quad.items())
        for k, a in quad.items():
            m, r = line.get(k, 0.0) / (-2 * a), np.sqrt(max(rhs, 0.0) / -a)
            lo[cols[k]], hi[cols[k]] = max(lo[cols[k]], m - r), min(hi[cols[k]], m + r)
    if lin:
        A = -np.array(lin)
        for i in range(len(vars)):
            for sgn, side in ((1, lo), (-1, hi)):
                res = linprog(sgn * np.eye(len(vars))[i], A_ub=A[:, :-1], b_ub=-A[:, -1], bounds=(None, None),
                              method="highs")
                if res.status == 0:
                    side[i] = max(side[i], res.fun) if sgn == 1 else min(side[i], -res.fun)
    return (lo, hi) if np.isfinite(lo).all() and np.isfinite(hi).all() else None


def variable_bounds(K: BasicSet, vars) -> np.ndarray | None:
    """R with |x_i| <= R_i on K (:func:`variable_box`), or None."""
    box = variable_box(K, vars)
    return None if box is None else np.maximum(np.abs(box[0]), np.abs(box[1]))


def _along(p: Polynomial, x0, r) -> list:
    """The exact coefficients (Fractions, in s) of p(x0 + s r) for rational x0, r."""
    out = [Fraction(0)] * (max(p.degree, 0) + 1)
    for e, c in zip(p.exps, p.coef[:, 0]):
        poly = [Fraction(c)]
        for k, power in enumerate(e):
            for _ in range(int(power)):                       # times (x0_k + s r_k)
                poly = [a * x0[k] + (poly[d - 1] * r[k] if d else 0)
                        for d, a in enumerate(poly)] + [poly[-1] * r[k]]
        for d, a in enumerate(poly):
            out[d] += a
    return out


def unbounded_ray(f: Polynomial, K: BasicSet):
    """(x0, r) with x0 + s r in K for every s >= 0 and f(x0 + s r) -> -inf, or None.

    A proof that f has no finite lower bound on K: every g_i(x0 + s r) has only nonnegative
    coefficients in s, every h_j(x0 + s r) is 0, and f(x0 + s r) has a negative leading
    coefficient (all in rational arithmetic). Tried: x0 on the integer grid {-2..2}^n (n <= 3; else
    0 and +-e_i), r among +-e_i and +-e_i +- e_j."""
    vars = f.vars + tuple(v for v in K.vars if v not in f.vars)
    n = len(vars)
    if not n or n > 8:
        return None
    polys = [p.with_vars(vars) for p in (f,) + K.ineqs + K.eqs]
    if any(p.ids.size for p in polys):
        return None
    f, ineqs, eqs = polys[0], polys[1:1 + len(K.ineqs)], polys[1 + len(K.ineqs):]
    I = np.eye(n, dtype=np.int64)
    starts = list(product(range(-2, 3), repeat=n)) if n <= 3 else [tuple(v) for v in np.vstack([0 * I[:1], I, -I])]
    rays = [tuple(v) for v in np.vstack([I, -I])]
    rays += [tuple(s * I[i] + t * I[j]) for i in range(n) for j in range(i + 1, n) for s in (1, -1) for t in (1, -1)]
    for x0 in starts:
        point = np.array(x0, dtype=float)[None, :]
        if any(g(point, vars)[0] < 0 for g in ineqs) or any(h(point, vars)[0] != 0 for h in eqs):
            continue
        q0 = [Fraction(int(v)) for v in x0]
        for r in rays:
            rq = [Fraction(int(v)) for v in r]
            along = _along(f, q0, rq)
            top = next((a for a in reversed(along[1:]) if a), 0)
            if top >= 0:
                continue
            if all(min(_along(g, q0, rq)) >= 0 for g in ineqs) and all(not any(_along(h, q0, rq)) for h in eqs):
                return np.array(x0, dtype=float), np.array(r, dtype=float)
    return None


def substituted(p: Polynomial, center, half) -> tuple[Polynomial, float, Polynomial]:
    """(q, err, d): q(u) the float coefficients of p(center + half * u), computed exactly then
    rounded; d the bounds of those roundings, monomial by monomial (|q_a - exact_a| <= d_a), and err
    their sum, so |q(u) - p(center + half u)| <= d(|u|) everywhere and <= err on the unit box."""
    vars = p.vars
    total: dict = {}
    for e, c in zip(p.exps, p.coef[:, 0]):
        terms = {(): Fraction(c)}
        for k, power in enumerate(e):
            binom = [Fraction(math.comb(int(power), j)) * Fraction(center[k]) ** (int(power) - j)
                     * Fraction(half[k]) ** j for j in range(int(power) + 1)]
            terms = {key + (j,): a * b for key, a in terms.items() for j, b in enumerate(binom) if b}
        for key, a in terms.items():
            total[key] = total.get(key, 0) + a
    keys = [k for k, a in total.items() if a]
    coef = [float(total[k]) for k in keys]
    rounding = [math.nextafter(float(abs(total[k] - Fraction(c))), math.inf) for k, c in zip(keys, coef)]
    err = float(sum(abs(total[k] - Fraction(c)) for k, c in zip(keys, coef)))
    exps = np.array(keys, dtype=np.int64).reshape(-1, len(vars)) if keys else np.zeros((1, len(vars)), dtype=np.int64)
    q = Polynomial(vars, exps, coef if keys else [0.0])
    d = Polynomial(vars, exps, [r if r > 5e-324 else 0.0 for r in rounding] if keys else [0.0])
    return q, math.nextafter(err, math.inf) * (1 + 1e-12) if err else 0.0, d


def as_set(ineqs=(), eqs=()) -> BasicSet:
    """A BasicSet from either a BasicSet (then ``eqs`` must be empty) or lists of polynomials."""
    if isinstance(ineqs, BasicSet):
        if len(eqs):
            raise InputError("pass the equalities inside the BasicSet, not next to it. "
                             "Try: BasicSet(ineqs=[...], eqs=[...])")
        return ineqs
    return BasicSet(ineqs, eqs)


def preorder(ineqs, products) -> list:
    """(index tuple S, g_S) for every S of size 1..order: order 1 for products=False,
    all sizes for products=True, at most ``products`` for an int."""
    if not (products is None or isinstance(products, (bool, int, np.integer))):
        raise InputError(f"products must be True, False or an integer order >= 1, got {products!r}")
    order = 1 if products is False or products is None else (len(ineqs) if products is True else int(products))
    if order < 1:
        raise InputError(f"products must be True, False or an order >= 1, got {products!r}")
    out = []
    for size in range(1, min(order, len(ineqs)) + 1):
        for S in combinations(range(len(ineqs)), size):
            g = ineqs[S[0]]
            for i in S[1:]:
                g = g * ineqs[i]
            out.append((S, g))
    return out


def degree_bounds(degree, count: int, default: int) -> list:
    """The degree bound of each of ``count`` constraints: ``degree`` an int, None (``default``),
    a list of ``count`` ints, or a dict {index: int} (others ``default``)."""
    if isinstance(degree, (bool, np.bool_, float, str)):
        raise InputError(f"degree must be an int, a list of ints or a dict {{index: int}}, got {degree!r}. "
                         "Try: degree=4")
    if degree is None or _is_int(degree):
        return [int(default if degree is None else degree)] * count
    if isinstance(degree, dict):
        bad = [k for k in degree if not (isinstance(k, int) and 0 <= k < count)]
        if bad:
            raise InputError(f"degree dict keys {bad} are not constraint indices 0..{count - 1} "
                             "(inequalities first, then equalities)")
        return [_checked_degree(degree.get(k, default)) for k in range(count)]
    if not isinstance(degree, (list, tuple, np.ndarray)):
        raise InputError(f"degree must be an int, a list of ints or a dict {{index: int}}, got {degree!r}. "
                         "Try: degree=4")
    degree = list(degree)
    if len(degree) != count:
        raise InputError(f"degree list has {len(degree)} entries for {count} constraints. Try: one "
                         "degree per inequality then per equality, or a dict {index: degree}")
    return [_checked_degree(d) for d in degree]


def _is_int(d) -> bool:
    return isinstance(d, (int, np.integer)) and not isinstance(d, (bool, np.bool_))


def _checked_degree(d) -> int:
    if not _is_int(d):
        raise InputError(f"a degree must be an int, got {d!r}. Try: degree=4")
    return int(d)


def putinar_terms(K: BasicSet, degree, products, default: int) -> list:
    """(kind, label, constraint, multiplier degree) of every Putinar term of K.

    kind "sos" for an inequality product g_S (even multiplier degree, the largest with
    deg(sigma) + deg(g_S) <= the bound: for a product, the largest bound of its factors), "free"
    for an equality. Single constraints whose degree exceeds their bound raise; products that
    do not fit are left out (they only strengthen a certificate).
    """
    m = len(K.ineqs)
    bounds = degree_bounds(degree, m + len(K.eqs), default)
    out = []
    for S, g in preorder(K.ineqs, products):
        d = max(bounds[i] for i in S) - g.degree
        d -= d % 2
        if d < 0 and len(S) == 1:
            raise PolynomialError(f"degree {bounds[S[0]]} is below the degree of constraint g{S[0]} "
                                  f"({g.degree}). Try: degree >= {g.degree}")
        if d >= 0:
            out.append(("sos", "sigma" + "_".join(str(i) for i in S), g, d))
    for k, h in enumerate(K.eqs):
        d = bounds[m + k] - h.degree
        if d < 0:
            raise PolynomialError(f"degree {bounds[m + k]} is below the degree of equality h{k} "
                                  f"({h.degree}). Try: degree >= {h.degree}")
        out.append(("free", f"lambda{k}", h, d))
    return out
