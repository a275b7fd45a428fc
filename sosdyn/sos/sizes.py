"""Size estimates of SOS building blocks, compared with ``limits.max_bytes`` before allocating."""
from __future__ import annotations

from ..limits import check_bytes


def family_bytes(terms) -> float:
    """Estimated bytes of :meth:`SOSProgram.add_sos_matrix_family`'s dense term tensor: terms x
    (monomials of y^T T y, at most r^2 x the largest entry's term count) x (1 + decisions), 8 each."""
    r = terms[0].shape[0]
    monos = r * r * max(len(e.exps) for t in terms for e in t.entries.flat)
    ids = len({int(i) for t in terms for e in t.entries.flat for i in e.ids})
    return 8.0 * len(terms) * monos * (1 + ids)


def check_family_size(terms, name) -> None:
    """ResourceLimitError before the family's tensor is allocated if it exceeds max_bytes."""
    check_bytes(family_bytes(terms), f"the SOS matrix family {name!r} ({len(terms)} terms)",
                "fewer terms, a lower degree or fewer states")
