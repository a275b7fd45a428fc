"""problems.lasa_corrective: the corrective variants of the ds-opt LASA run build the right estimator."""
from problems import lasa_corrective, lasa_dsopt
from sosdyn.lfd.cdsp import CDSP
from sosdyn.lfd.corrective import CorrectiveCDSP


def test_problem_variants_build_the_right_estimator():
    plain = lasa_corrective.make_estimator({"n_components": 3})
    assert isinstance(plain, CDSP) and plain.n_components == 3
    corr = lasa_corrective.make_estimator({"n_components": 3, lasa_corrective.CORRECTIVE: 2})
    assert isinstance(corr, CorrectiveCDSP) and corr.rounds == 2 and corr.cdsp_params == {"n_components": 3}
    assert corr.start_index == 19 and corr.score is lasa_corrective.training_dtwd
    key = lasa_corrective.estimator_params({"gamma": 0.02, lasa_corrective.CORRECTIVE: 2})
    assert key["gamma"] == 0.02 and key[lasa_corrective.CORRECTIVE] == 2 and key["tau"] == lasa_corrective.TAU
    assert lasa_corrective.CORRECTIVE not in lasa_corrective.estimator_params({"gamma": 0.02})


def test_corrective_variants_are_registered():
    assert set(lasa_corrective.VARIANTS) <= set(lasa_dsopt.VARIANTS)
    assert lasa_dsopt.SELECTIONS["CDSP corrective selected"] == tuple(lasa_corrective.VARIANTS)
    assert lasa_dsopt.VARIANTS["CDSP default"] == {}                # the existing variants are kept
