"""The python blocks of the SOS feature pages run as written (each block on its own)."""
import re
from pathlib import Path

import pytest

PAGES = ["sos-moments.md", "sos-semantics.md", "sos-sets.md", "sos-sparsity.md"]
DOCS = Path(__file__).resolve().parents[2] / "docs"


def blocks(page):
    return re.findall(r"```python\n(.*?)```", (DOCS / page).read_text(), flags=re.S)


@pytest.mark.parametrize("page,k,code", [(p, k, c) for p in PAGES for k, c in enumerate(blocks(p))])
def test_docs_code_block_runs(page, k, code):
    exec(compile(code, f"{page}#{k}", "exec"), {})


def test_every_page_has_examples():
    assert all(len(blocks(p)) >= 3 for p in PAGES)
