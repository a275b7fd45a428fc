"""Gram bases from the Newton polytope, and the size check of coefficient matching."""
import pytest

import sosdyn as sd
from sosdyn.sos import newton_basis
from sosdyn.sos.newton import gram_matching_bytes

x, y = sd.variables("x y")


def test_newton_basis_of_a_homogeneous_form():
    x, y = sd.variables("x y")
    p = x**6 + y**6
    b = newton_basis(p.exps)
    assert {tuple(r) for r in b} == {(3, 0), (2, 1), (1, 2), (0, 3)}


def test_gram_matching_is_checked_before_it_allocates():
    assert gram_matching_bytes(66, 2) == 8.0 * 2211 * 16
    with sd.limits(max_bytes=int(gram_matching_bytes(66, 2)) - 1):
        with pytest.raises(sd.ResourceLimitError, match="Gram basis of 66 monomials"):
            sd.SOSProgram().add_sos((1 + x**2 + y**2) ** 10)
    assert len(sd.SOSProgram().add_sos((1 + x**2 + y**2) ** 10).basis) == 66
