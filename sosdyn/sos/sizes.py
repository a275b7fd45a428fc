"""Size estimates of SOS building blocks, compared with ``limits.max_bytes`` before allocating."""
from __future__ import annotations

from ..limits import check_bytes


def family_bytes(terms) -> float:
    """Bytes of :meth:`SOSProgram.add_sos_matrix_family`'s dense term tensor, an upper bound:
    8 x (terms) x (monomials of sum_t y^T T_t y) x (1 + decision ids), the monomials counted
    as sum over entries (i <= j) of the union over t of T_t[i, j]'s monomials (by name)."""
    r = terms[0].shape[0]
    monos, ids = 0, set()
    for i in range(r):
        for j in range(i, r):
            seen = set()
            for t in terms:
                e = t.entries[i, j]
                ids.update(int(k) for k in e.ids)
                seen.update(tuple((v, int(a)) for v, a in zip(e.vars, row) if a) for row in e.exps.tolist())
            monos += len(seen)
    return 8.0 * len(terms) * monos * (1 + len(ids))


def check_family_size(terms, name) -> None:
    """ResourceLimitError before the family's tensor is allocated if it exceeds max_bytes."""
    check_bytes(family_bytes(terms), f"the SOS matrix family {name!r} ({len(terms)} terms)",
                "fewer terms, a lower degree or fewer states")
