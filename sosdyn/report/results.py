"""Results files: the schema check of a results dict and the guarded reading of a
``results.json`` (size, depth, JSON, schema). The schema is in :mod:`sosdyn.report.html`."""
from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path

from ..errors import InputError
from ..limits import check_count, check_json_depth, get_limits

_JSON_KINDS = {"object": Mapping, "array": list, "string": str, "boolean": bool, "number": (int, float),
               "null": type(None)}
# JSON kind of each top-level value of a results file (null also allowed); the first two are required.
_SECTION_KINDS = {"meta": "object", "pages": "array", "findings": "array", "methods": "object",
                  "accuracy": "object", "robustness": "object", "certificates": "object",
                  "timings": "object", "diagnostics": "object", "figures": "object"}
_REQUIRED_SECTIONS = ("meta", "findings")
RESULTS_HINT = ("pass the results.json written by `python -m problems run` (or `make run`), "
                 "e.g. reports/results.json")


def _json_kind(value) -> str:
    return next(kind for kind, types in _JSON_KINDS.items() if isinstance(value, types))


def check_results(results, source: str = "results") -> dict:
    """``results`` if it is a results dict (module docstring), else InputError naming every
    missing, unexpected or mistyped top-level key."""
    if not isinstance(results, Mapping):
        raise InputError(f"{source} holds a JSON {_json_kind(results)}, expected a JSON object. "
                         f"Try: {RESULTS_HINT}.")
    problems = []
    missing = [k for k in _REQUIRED_SECTIONS if results.get(k) is None]
    if missing:
        problems.append(f"no {' or '.join(map(repr, missing))}")
    unknown = sorted(set(results) - set(_SECTION_KINDS))
    if unknown:
        problems.append(f"unexpected key(s) {', '.join(map(repr, unknown[:8]))}{' ...' if len(unknown) > 8 else ''}")
    for key, kind in _SECTION_KINDS.items():
        value = results.get(key)
        if value is not None and not isinstance(value, _JSON_KINDS[kind]):
            problems.append(f"{key!r} should be a JSON {kind}, not {_json_kind(value)}")
    if isinstance(results.get("findings"), list) and not all(isinstance(f, Mapping) for f in results["findings"]):
        problems.append("'findings' holds non-objects")
    if problems:
        raise InputError(f"{source} is not a sosdyn results file ({'; '.join(problems)}). Try: {RESULTS_HINT}.")
    return dict(results)


def load_results(path: str | Path) -> dict:
    """Read and check a results JSON (:func:`check_results`): a missing file raises
    FileNotFoundError; a file over ``max_file_bytes`` or nested deeper than ``max_json_depth``
    ResourceLimitError (before parsing); bad JSON or a wrong schema InputError."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"results file not found: {path}")
    size_of = f"the size of {path} in bytes"
    with path.open("rb") as file:
        check_count(os.fstat(file.fileno()).st_size, "max_file_bytes", size_of, RESULTS_HINT)
        data = file.read(get_limits().max_file_bytes + 1)      # never more, even if it grows
    check_count(len(data), "max_file_bytes", size_of, RESULTS_HINT)
    check_json_depth(data, str(path), RESULTS_HINT)
    try:
        results = json.loads(data.decode("utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"{path} is not valid JSON ({exc}). Try: re-run the experiment that writes it.") from exc
    return check_results(results, str(path))
