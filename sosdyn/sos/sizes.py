"""Size estimates of SOS building blocks, compared with ``limits.max_bytes`` before allocating."""
from __future__ import annotations

from ..limits import check_bytes


def family_bytes(n_terms: int, n_monomials: int, n_ids: int) -> float:
    """Bytes of the dense term tensor of :class:`~.constraints.FamilySOSConstraint`: one float per
    (term, monomial of sum_t y^T T_t y, constant or decision id)."""
    return 8.0 * n_terms * n_monomials * (1 + n_ids)


def check_family_size(n_terms: int, n_monomials: int, n_ids: int, name) -> None:
    """ResourceLimitError before the family's tensor is allocated if it exceeds max_bytes."""
    check_bytes(family_bytes(n_terms, n_monomials, n_ids),
                f"the SOS matrix family {name!r} ({n_terms} terms, {n_monomials} monomials, {n_ids} decisions)",
                "fewer terms, a lower degree or fewer states")
