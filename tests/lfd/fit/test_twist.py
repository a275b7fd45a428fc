"""The twist about the goal (sosdyn.lfd.fit.twist) and the warp it composes with (sosdyn.lfd.fit.composite).

References from outside the code under test: central finite differences, numpy's solve / svd / det,
and the closed-form spiral of a twisted linear system."""
import hashlib
import json
from types import SimpleNamespace

import numpy as np
import pytest

from sosdyn.errors import InputError, ModelFileError
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations
from sosdyn.lfd.fit import composite, pipeline
from sosdyn.lfd.fit import twist as tw
from sosdyn.lfd.fit.composite import TWIST_TERMS
from sosdyn.lfd.fit.warp import AUTO_WARPS, ESCALATE_WARPS
from sosdyn.lfd.model.cdsp import CDSP
from sosdyn.lfd.model.fileformat import canonical
from sosdyn.lfd.model.files import load_model
from sosdyn.lfd.model.reach import reach_box
from sosdyn.lfd.runtime.predictor import twist_back, twist_forward, twist_tables


def random_twist(n, seed=0, terms=5, size=2.0):
    rng = np.random.default_rng(seed)
    plane = np.linalg.qr(rng.normal(size=(n, 2)))[0].T
    return plane, size * rng.normal(size=terms), np.geomspace(0.1, 2.0, terms)


@pytest.mark.parametrize("n", [2, 3, 6])
def test_a_twist_is_a_volume_preserving_diffeomorphism_fixing_the_goal(n):
    t = random_twist(n, seed=n)
    Z = np.random.default_rng(1).normal(size=(200, n))
    U, J = tw.jacobian(Z, *t)
    assert np.allclose(tw.apply(Z, *t), U, atol=1e-15, rtol=0)
    assert np.abs(tw.invert(U, *t) - Z).max() < 1e-13
    assert np.abs(np.linalg.norm(U, axis=1) - np.linalg.norm(Z, axis=1)).max() < 1e-13     # |T(z)| = |z|
    assert np.abs(np.linalg.det(J) - 1.0).max() < 1e-12
    assert np.array_equal(tw.apply(np.zeros((1, n)), *t), np.zeros((1, n)))
    h = 1e-6
    fd = np.stack([(tw.apply(Z + h * e, *t) - tw.apply(Z - h * e, *t)) / (2 * h) for e in np.eye(n)], axis=2)
    assert np.abs(J - fd).max() < 1e-7
    f = lambda X: np.sin(X) + X ** 2           # noqa: E731
    assert np.abs(tw.pulled_back(Z, *t, f) - np.linalg.solve(J, f(U)[..., None])[..., 0]).max() < 1e-12


@pytest.mark.parametrize("n", [2, 4])
def test_singular_values_lie_within_the_closed_form_bound_which_one_term_attains(n):
    """1/lam(K) <= sigma(J_T) <= lam(K), K = (2/e) sum |a_j|; for one term the sup of |r alpha'| is
    (2/e)|a| at r = tau, in the plane, so a dense radial grid there reaches lam(K)."""
    t = random_twist(n, seed=7, size=3.0)
    Z = np.random.default_rng(2).uniform(-3, 3, (5000, n))
    sv = np.linalg.svd(tw.jacobian(Z, *t)[1], compute_uv=False)
    low = tw.singular_bound(t[1])
    assert sv.min() >= low * (1 - 1e-12) and sv.max() <= (1 / low) * (1 + 1e-12)
    plane, a, tau = t[0], np.array([2.5]), np.array([0.7])
    r = np.linspace(0.01, 3, 3001)[:, None] * plane[0]              # along p, in the plane
    sv = np.linalg.svd(tw.jacobian(r, plane, a, tau)[1], compute_uv=False)
    K = 2 * 2.5 / np.e
    assert sv[:, 0].max() == pytest.approx((K + np.sqrt(K * K + 4)) / 2, rel=1e-5)
    assert tw.shear_bound(a) == pytest.approx(K)


def spiral(t, r0, th0, a, tau):
    """The closed form: u = r0 e^{-t} (cos th0, sin th0) solves udot = -u; z = T^{-1}(u) is at radius
    rho = r0 e^{-t} and angle th0 - alpha(rho), with velocity rhodot (c, s) + rho phidot (-s, c),
    rhodot = -rho, phidot = -alpha'(rho) rhodot."""
    rho = r0 * np.exp(-t)
    e = np.exp(-rho[:, None] ** 2 / tau ** 2)
    alpha, dalpha = (a * (1 - e)).sum(axis=1), (a * 2 * rho[:, None] / tau ** 2 * e).sum(axis=1)
    phi = th0 - alpha
    c, s = np.cos(phi), np.sin(phi)
    pos = rho[:, None] * np.column_stack([c, s])
    vel = -rho[:, None] * np.column_stack([c, s]) + (rho * dalpha * rho)[:, None] * np.column_stack([-s, c])
    return pos, vel


def twisted_demos(a, tau, goal=np.array([1.0, -2.0])):
    t = np.linspace(0, 12, 400)                  # ends within 1e-5 of the goal
    demos = [Demonstration(t, goal + p, v, f"spiral {k}") for k, (r0, th0) in
             enumerate(((1.0, 0.3), (0.8, 1.9), (1.2, 3.4), (0.9, 4.9)))
             for p, v in [spiral(t, r0, th0, a, tau)]]
    return Demonstrations(demos, "twisted", "m")


def test_the_fit_recovers_alpha_of_an_exactly_twisted_system_and_the_rollout_is_its_spiral():
    """Demonstrations of u' = -u seen through T^{-1} (alpha winding 1.7 rad from r = 1.2 in): the fitted
    twist's alpha is the true one (widths on the fit's own grid), and CDSP through it (no bumps, one
    linear component) rolls out the closed-form spiral from a new start; the plain fit does not."""
    grid = 1.2 * np.geomspace(*tw.TAU_RANGE, TWIST_TERMS)
    a, tau = np.array([2.0, -0.5]), grid[[6, 9]]
    demos = twisted_demos(a, tau)
    curves = [d.pos[::3] - demos.goal for d in demos]
    plane, a_fit, tau_fit = tw.fit_twist(curves, TWIST_TERMS, 0.0, 10.0)       # no ridge: exact data
    r = np.linspace(0, 1.2, 200)
    true, fitted = tw.angle(r ** 2, a, tau)[0], tw.angle(r ** 2, a_fit, tau_fit)[0]
    assert np.allclose(np.abs(plane @ plane.T), np.eye(2))
    sign = np.sign(np.linalg.det(plane))                         # the fit's plane may be (e1, -e2): alpha flips
    assert np.abs(sign * fitted - true).max() < 1e-4, np.abs(sign * fitted - true).max()     # measured 1.4e-6
    m = CDSP(n_components=1, warp={"n_maps": 0, "twist": 5.0}, corrective_rounds=0, random_state=0).fit(demos)
    plain = CDSP(n_components=1, warp="none", corrective_rounds=0, random_state=0).fit(demos)
    assert m.certified_ and len(m.warp_["sigmas"]) == 0 and "twist" in m.warp_
    t = np.linspace(0, 6, 61)
    exact = demos.goal + spiral(t, 1.1, 2.6, a, tau)[0]
    errs = {name: np.abs(model.rollout(exact[0], 6.0, dt=0.1).pos - exact).max() for name, model in
            (("twist", m), ("plain", plain))}
    assert errs["twist"] < 0.01 and errs["plain"] > 0.05, errs     # r0 = 1.1; measured 2.6e-4 and 0.14


def test_the_plane_of_a_twist_in_3d_is_recovered():
    """Spirals in a tilted plane of R^3: the fitted plane spans it."""
    rng = np.random.default_rng(3)
    basis = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    t = np.linspace(0, 6, 200)
    curves = []
    for r0, th0 in ((1.0, 0.3), (0.8, 2.0), (1.1, 4.0)):
        p, _ = spiral(t, r0, th0, np.array([2.0]), np.array([0.5]))
        curves.append(p @ basis[:, :2].T)
    plane = tw.fit_plane(curves)
    assert np.allclose(plane @ plane.T, np.eye(2), atol=1e-12)
    assert np.allclose(np.linalg.svd(plane @ basis[:, :2], compute_uv=False), 1.0, atol=1e-12)


def test_the_fit_meets_the_shear_bound():
    demos = twisted_demos(np.array([6.0, -3.0]), np.array([0.3, 0.9]))
    for bound in (0.5, 2.0):
        _, a, _ = tw.fit_twist([d.pos - demos.goal for d in demos], TWIST_TERMS, 1e-10, bound)
        assert tw.shear_bound(a) <= bound * (1 + 1e-12)


@pytest.mark.parametrize("bad, match", [
    ((np.array([[1.0, 0.0], [0.5, 1.0]]), [1.0], [1.0]), "orthonormal"),
    ((np.eye(2), [1.0], [-1.0]), "width > 0"),
    ((np.eye(2), [np.nan], [1.0]), "finite"),
    ((np.eye(3), [1.0], [1.0]), "shapes"),
    ((np.eye(2), [1.0, 2.0], [1.0]), "shapes"),
    ((np.eye(2), np.ones(65), np.ones(65)), "terms"),
    ((np.eye(2), [1e7], [1.0]), "ill-conditioned"),
])
def test_bad_twist_arrays_are_input_errors(bad, match):
    with pytest.raises(InputError, match=match):
        tw.check_twist(*bad)


def test_the_warp_check_recomputes_the_twist_bound_and_flags_a_forged_twist():
    C, V, S = np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0)
    warp = {"centers": C, "vectors": V, "sigmas": S, "twist": {"plane": np.eye(2), "amplitudes": np.array([1.5]),
                                                              "widths": np.array([0.5])}}
    rep = composite.check(warp, 2000, 0)
    assert rep["passed"] and rep["twist_shear"] == pytest.approx(3 / np.e)
    assert rep["twist_min_singular"] >= rep["twist_singular_bound"] == rep["singular_bound"]
    warp["twist"]["plane"] = np.array([[1.0, 0.0], [0.1, 1.0]])          # not a rotation any more
    rep = composite.check(warp, 2000, 0)
    assert not rep["passed"] and rep["twist_shear"] == np.inf


@pytest.mark.parametrize("n", [2, 3])
def test_predictor_twist_passes_are_T_and_the_inverse_jacobian(n):
    t = random_twist(n, seed=11)
    T = twist_tables(*t)
    rng = np.random.default_rng(n)
    for w in rng.uniform(-2, 2, (20, n)):
        U, J = tw.jacobian(w[None], *t)
        u, turn = twist_forward(T, w.tolist())
        v = rng.normal(size=n)
        assert np.abs(np.array(u) - U[0]).max() < 1e-14
        assert np.abs(np.array(twist_back(T, turn, v.tolist())) - np.linalg.solve(J[0], v)).max() < 1e-12


def test_per_row_twists_are_each_rows_own():
    """block_pull: three blocks (a twist with bumps, none, a twist alone) in one pass give what each
    block's own pulled_back gives."""
    rng = np.random.default_rng(5)
    one = {"centers": np.array([[0.3, 0.1]]), "vectors": np.array([[0.1, -0.05]]), "sigmas": np.array([0.6]),
           "twist": dict(zip(("plane", "amplitudes", "widths"), random_twist(2, seed=1)))}
    two = {"centers": np.zeros((0, 2)), "vectors": np.zeros((0, 2)), "sigmas": np.zeros(0),
           "twist": dict(zip(("plane", "amplitudes", "widths"), random_twist(2, seed=2, terms=3)))}
    Z = rng.uniform(-1, 1, (6, 2))
    f = lambda X: -X + 0.3 * X[:, ::-1]         # noqa: E731
    both = composite.block_pull([one, None, two], 2, 2)(Z, f)
    alone = np.vstack([composite.pulled_back(Z[:2], one, f), f(Z[2:4]), composite.pulled_back(Z[4:], two, f)])
    assert np.abs(both - alone).max() < 1e-14
    assert composite.block_pull([None, None], 3, 2) is None


@pytest.fixture(scope="module")
def twisted_model():
    grid = 1.2 * np.geomspace(*tw.TAU_RANGE, TWIST_TERMS)
    demos = twisted_demos(np.array([2.0, -0.5]), grid[[6, 9]])
    return CDSP(n_components=2, warp={"n_maps": 5, "twist": 5.0}, corrective_rounds=0, random_state=0,
                verify_samples=1000).fit(demos)


def test_a_twisted_model_file_round_trips_and_a_forged_twist_does_not_load(twisted_model, tmp_path):
    m = twisted_model
    assert m.certified_ and "twist" in m.warp_ and m.verification_.warp["twist_shear"] <= 5.0 * (1 + 1e-12)
    back = load_model(m.save(tmp_path / "twist.json"))
    X = m.goal_ + np.random.default_rng(3).uniform(-1.5, 1.5, (40, 2))
    assert np.array_equal(back.predict(X), m.predict(X)) and back.certified_
    doc = json.loads((tmp_path / "twist.json").read_text())
    for edit, match in ((lambda t: t.update(plane=[[1.0, 0.0], [0.2, 1.0]]), "orthonormal"),
                        (lambda t: t.update(widths=t["widths"][:-1]), "twist.amplitudes|twist.widths"),
                        (lambda t: t.update(extra=1), "exactly")):
        bad = json.loads(json.dumps(doc))
        edit(bad["state"]["warp_"]["twist"])
        bad.pop("sha256")
        bad["sha256"] = hashlib.sha256(canonical(bad)).hexdigest()      # a deliberate edit, checksum redone
        path = tmp_path / "bad.json"
        path.write_text(json.dumps(bad))
        with pytest.raises(ModelFileError, match=match):
            load_model(path)


def test_a_twisted_models_rollouts_stay_in_their_reach_box(twisted_model):
    m = twisted_model
    starts = m.goal_ + np.array([[1.1, 0.2], [-0.6, 0.9], [1.6, -1.4]])
    lo, hi = reach_box(m, starts)
    for x0, a, b in zip(starts, lo, hi):
        pos = m.rollout(x0, 8.0, dt=0.02).pos
        assert (pos >= a - 1e-9).all() and (pos <= b + 1e-9).all()


def test_the_reach_box_of_a_twist_is_the_disc_of_the_level_set():
    """M = diag(4, 1), goal 0, scale 2, x0 = (2, 2), no bumps and a zero twist (T = id): V0 = 5 and the
    twist may turn u by any angle, so each coordinate is bounded by the disc's radius sqrt(V0 / 1)."""
    warp = {"centers": np.zeros((0, 2)), "vectors": np.zeros((0, 2)), "sigmas": np.zeros(0),
            "twist": {"plane": np.eye(2), "amplitudes": np.zeros(1), "widths": np.ones(1)}}
    model = SimpleNamespace(W_=np.diag([4.0, 1.0])[:, :, None], metric_exps_=np.zeros((1, 2), dtype=np.int64),
                            dim_=2, goal_=np.zeros(2), scale_=2.0, warp_=warp)
    lo, hi = reach_box(model, np.array([[2.0, 2.0]]))
    assert np.allclose(hi, 2 * np.sqrt(5.0)) and np.allclose(lo, -hi)


def test_the_default_escalates_only_past_its_threshold(monkeypatch):
    """warp='auto' adds ESCALATE_WARPS only when the kept candidate's training deviation exceeds
    ESCALATE x the data's diagonal: never with an infinite threshold, always with 0; the kept fit is
    the certified one of lowest score among all candidates fitted."""
    demos = twisted_demos(np.array([2.0]), np.array([0.6]))
    small = {"n_components": 2, "max_samples": 300, "verify_samples": 500, "random_state": 0}
    monkeypatch.setattr(pipeline, "ESCALATE", np.inf)
    assert set(CDSP(**small).fit(demos).warp_scores_) == {"none", *AUTO_WARPS}
    monkeypatch.setattr(pipeline, "ESCALATE", 0.0)
    m = CDSP(**small).fit(demos)
    scores = m.warp_scores_
    assert set(scores) == {"none", *AUTO_WARPS, *ESCALATE_WARPS} and m.certified_
    best = min(scores, key=scores.get)
    fixed = CDSP(**small, warp="none" if best == "none" else {**AUTO_WARPS, **ESCALATE_WARPS}[best]).fit(demos)
    assert np.array_equal(m.predict(demos[0].pos), fixed.predict(demos[0].pos))
