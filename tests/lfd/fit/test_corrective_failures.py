"""Corrective refits that cannot help (issue 23, item 5): a corrective_tau shorter than the data's
sample step is refused before any fit; a refit that fails keeps the certified rounds and says so."""
import numpy as np
import pytest

import sosdyn as sd
from sosdyn.errors import InfeasibleError, InputError
from sosdyn.lfd.fit import pipeline as cdsp_module

SMALL = {"n_components": 1, "gamma": 0.5, "max_iter": 5, "verify_samples": 500, "warp": "none"}


@pytest.mark.parametrize("tau", [1e-12, 1e-6, 0.03])
def test_a_tau_below_the_sample_step_is_refused_before_any_fit(tau, linear_demos, monkeypatch):
    """The linear demos are sampled every 6/199 = 0.0302 s (tau = 1e-12 was an UnboundedError
    from the refit's dynamics step, 1e-6 an InfeasibleError, each aborting the whole fit)."""
    monkeypatch.setattr(cdsp_module, "fit_joint_gmm", lambda *a: pytest.fail("EM ran before the check"))
    with pytest.raises(InputError, match=r"corrective_tau = .* is shorter than the demonstrations' sample step "
                                         r"0.0301508 s.* Try: corrective_tau >= 0.0302"):
        sd.CDSP(**SMALL, corrective_rounds=1, corrective_tau=tau).fit(linear_demos)


def test_a_tau_below_the_sample_step_is_fine_without_rounds(linear_demos):
    assert sd.CDSP(**SMALL, corrective_tau=1e-12).fit(linear_demos).certified_


def test_a_failing_refit_keeps_round_zero_and_says_so(linear_demos, monkeypatch):
    """The refit's solve is made infeasible: the fit returns round 0 (the plain fit) with a warning."""
    real, calls = cdsp_module.fit_joint_gmm, []

    def infeasible_second(*args, **kwargs):
        calls.append(1)
        if len(calls) == 2:
            raise InfeasibleError("program 'ICA step' is infeasible", "infeasible")
        return real(*args, **kwargs)

    monkeypatch.setattr(cdsp_module, "fit_joint_gmm", infeasible_second)
    with pytest.warns(UserWarning, match=r"corrective round 1 failed \(InfeasibleError: program 'ICA step' is "
                                         r"infeasible\); keeping the best of rounds 0..0, all certified"):
        model = sd.CDSP(**SMALL, corrective_rounds=2).fit(linear_demos)
    monkeypatch.setattr(cdsp_module, "fit_joint_gmm", real)
    plain = sd.CDSP(**SMALL).fit(linear_demos)
    assert len(calls) == 2 and model.certified_ and model.corrective_round_ == 0
    assert len(model.corrective_scores_) == 1 and model.corrective_pairs_ == [284]
    np.testing.assert_array_equal(model.C_, plain.C_)


def test_too_long_demos_for_the_auto_scoring_are_refused_with_cdsp_remedies(linear_demos, monkeypatch):
    """4 demos x 201 steps over max_rollout_steps = 500, as a 1e7-sample demo is over the default 1e7:
    refused before any fit, the hint naming what a CDSP user can change (it said "lower max_steps",
    a parameter of euler_until_rest, not of CDSP)."""
    monkeypatch.setattr(cdsp_module, "fit_joint_gmm", lambda *a: pytest.fail("EM ran before the check"))
    with sd.limits(max_rollout_steps=500), pytest.raises(sd.ResourceLimitError) as info:
        sd.CDSP(n_components=1).fit(linear_demos)
    text = str(info.value)
    assert "The rollouts that score warp='auto' (4 demonstrations x 201 steps" in text and "is 804" in text
    assert "Try: fewer samples per demonstration (demos.subsample(k)), or warp='none'" in text
    assert "max_steps" not in text.replace("max_rollout_steps", "")
    monkeypatch.undo()
    with sd.limits(max_rollout_steps=500):
        assert sd.CDSP(**dict(SMALL, warp="auto", speed_floor="none")).fit(linear_demos.subsample(2)).certified_  # 4 x 101
        with pytest.raises(sd.ResourceLimitError, match=r"speed_floor='auto' \(4 demonstrations x 152 steps.*"
                           r"speed_floor='none' or a rate"):
            sd.CDSP(**dict(SMALL, warp="auto")).fit(linear_demos.subsample(2))    # 1.5 x 100 steps + 2
        assert sd.CDSP(**dict(SMALL, warp="auto")).fit(linear_demos.subsample(3)).certified_   # 4 x 101 floor steps
