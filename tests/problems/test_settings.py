"""problems.settings: the paper's shapes and the methods' estimators and settings."""
from __future__ import annotations

import sosdyn as sd
from problems.settings import DEFAULT_METHOD, METHOD_ORDER, METHODS, PAPER_SHAPES, shape
from problems.results import methods_section
from sosdyn.evaluation.baselines import CLFDM, DMP


def test_shapes_and_factories():
    assert [(s.name, s.K, s.dmp_basis) for s in PAPER_SHAPES][1] == ("DoubleBendedLine", 7, 35)
    assert shape("Sine") == shape("Sine", K=6) and shape("Leaf_2", K=3).dmp_basis == 35
    leaf = shape("Leaf_2")
    ica = METHODS["CDSP-ICA"].factory(leaf, quick=True)
    assert isinstance(ica, sd.CDSP) and ica.solver_method == "ica" and ica.max_iter == 4
    assert isinstance(METHODS["DMP"].factory(leaf), DMP) and isinstance(METHODS["CLF-DM"].factory(leaf), CLFDM)
    assert METHOD_ORDER[:2] == (DEFAULT_METHOD, "CDSP (paper)") and len(METHOD_ORDER) == 8   # the default first


def test_methods_section_writes_out_per_shape_values():
    section = methods_section(PAPER_SHAPES, ("DMP", "GMR"))
    assert section["DMP"]["settings"] == {"n_weights_per_dim": "BendedLine 25, DoubleBendedLine 35, "
                                                                "Leaf_1 25, Leaf_2 35"}
    assert section["GMR"]["settings"]["random_state"] == 0 and "LSODA" in section["GMR"]["settings"]["integrator"]
