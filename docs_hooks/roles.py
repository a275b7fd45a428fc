"""mkdocs hook: Sphinx cross-reference roles in docstrings (``:mod:`.warp```, ``:func:`~.x.f```)
are rendered as plain code, ``warp`` / ``f``, instead of raw ``:mod:`` markup.

mkdocstrings renders the docstrings as Markdown (``docstring_style: null``), where a role
arrives as ``:mod:<code>.warp</code>``; this keeps the code and drops the role and the
leading ``~`` / ``.`` (``~`` shows the last name, as in Sphinx).
"""
import re

ROLE = re.compile(r":(?:mod|func|class|meth|data|attr|exc|obj):<code>(~?)\.?([^<]*)</code>")


def _name(match: re.Match) -> str:
    tilde, target = match.groups()
    return f"<code>{target.rsplit('.', 1)[-1] if tilde else target}</code>"


def on_page_content(html: str, **_) -> str:
    return ROLE.sub(_name, html)
