"""Resource limits checked *before* work starts (solves, rollouts, file reads).

Every large allocation sosdyn makes on a user's behalf is estimated first and compared with
a limit here; over it, a :class:`~sosdyn.errors.ResourceLimitError` says the estimate, the
limit and how to raise it. Defaults suit a workstation (a few GiB); raise them for big
machines::

    import sosdyn as sd
    sd.set_limits(max_bytes=32 * 2**30)          # for the rest of the session
    with sd.limits(max_rollout_steps=10**8):      # for one block
        model.rollout(x0, duration=1e4)

The session starts from the defaults, each replaced by the environment variable ``SOSDYN_<NAME>``
when it is set (``SOSDYN_MAX_BYTES=34359738368 sosdyn fit ...``): the way to raise a limit for the
``sosdyn`` command. A value that is not a positive integer is an InputError when a limit is first read.
"""
from __future__ import annotations

import os
import re
from contextlib import contextmanager
from dataclasses import dataclass, fields, replace

import numpy as np

from .errors import InputError, ResourceLimitError


@dataclass(frozen=True)
class Limits:
    """The limits in force (see module docstring)."""

    max_bytes: int = 4 * 2**30            # estimated working memory of one solve or rollout
    max_rollout_steps: int = 10**7        # integration steps of one rollout (all starts)
    max_rollout_calls: int = 100_000      # field evaluations of one adaptive rollout
    max_rollout_seconds: int = 120        # wall-clock seconds of one adaptive rollout
    max_file_bytes: int = 64 * 2**20      # a model or results file read from disk
    max_json_depth: int = 64              # nesting depth accepted in a JSON file
    max_model_dim: int = 32               # state dimension n of a model file (a second-order state is 2n)
    max_model_components: int = 32       # mixture components K of a model file
    max_exact_work: int = 500_000         # rational multiply-adds of a file's exact certificate check, (K+1)(2n)^3
    max_sampled_work: int = 3 * 10**9     # multiply-adds of a file's sampled certificate check, S K n^2 (m + p)


ENV_PREFIX = "SOSDYN_"
_current: Limits | None = None         # read from the defaults and the environment when first needed


def env_name(name: str) -> str:
    """The environment variable of the limit ``name``: SOSDYN_MAX_BYTES for max_bytes."""
    return ENV_PREFIX + name.upper()


def _from_environment() -> Limits:
    """The defaults, each replaced by its environment variable when set (module docstring)."""
    changes = {}
    for f in fields(Limits):
        text = os.environ.get(env_name(f.name))
        if text is None:
            continue
        try:
            changes[f.name] = int(text.strip().replace("_", ""))
        except ValueError:
            raise InputError(f"the environment variable {env_name(f.name)} = {text!r:.40} is not an integer. "
                             f"Try: a positive integer (e.g. {getattr(Limits(), f.name)}), or unset it.") from None
    return _validated(replace(Limits(), **changes), "the environment variable ")


def get_limits() -> Limits:
    """The limits in force now."""
    global _current
    if _current is None:
        _current = _from_environment()
    return _current


def set_limits(**changes) -> Limits:
    """Change limits for the rest of the session; returns the previous ones."""
    global _current
    previous = get_limits()
    _current = _validated(replace(previous, **_checked_names(changes)))
    return previous


@contextmanager
def limits(**changes):
    """Temporarily change limits: ``with sd.limits(max_bytes=2**34): ...``."""
    previous = set_limits(**changes)
    try:
        yield get_limits()
    finally:
        _restore(previous)


def _restore(previous: Limits) -> None:
    global _current
    _current = previous


def _checked_names(changes: dict) -> dict:
    known = {f.name for f in fields(Limits)}
    unknown = sorted(set(changes) - known)
    if unknown:
        raise InputError(f"unknown limit(s) {unknown}; known: {sorted(known)}")
    return changes


def _validated(lim: Limits, where: str = "") -> Limits:
    for f in fields(Limits):
        v = getattr(lim, f.name)
        if isinstance(v, bool) or not isinstance(v, int) or v <= 0:
            name = env_name(f.name) if where else f"limit {f.name}"
            raise InputError(f"{where}{name} must be a positive integer, got {v!r}")
    return lim


def raise_hint(name: str) -> str:
    """How to raise the limit ``name``, in Python and for the ``sosdyn`` command."""
    return f"sosdyn.set_limits({name}=...) (the sosdyn command: {env_name(name)}=... in the environment)"


def format_bytes(n: float) -> str:
    """1.5 GiB, 320 MiB, 12 KiB: for messages."""
    for unit, size in (("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if n >= size:
            return f"{n / size:.1f} {unit}"
    return f"{int(n)} B"


def check_bytes(estimate: float, what: str, hint: str = "") -> None:
    """Raise ResourceLimitError if ``estimate`` bytes exceed ``max_bytes``."""
    limit = get_limits().max_bytes
    if not estimate <= limit:
        raise ResourceLimitError(
            f"{what} needs about {format_bytes(estimate)}, over the limit of {format_bytes(limit)}. "
            f"Try: {hint + '; or ' if hint else ''}raise the limit with "
            f"{raise_hint('max_bytes')} if this machine has the memory.")


def check_count(value: float, limit_name: str, what: str, hint: str = "") -> None:
    """Raise ResourceLimitError if ``value`` exceeds the named count limit."""
    limit = getattr(get_limits(), limit_name)
    if not value <= limit:
        raise ResourceLimitError(
            f"{what} is {value:.3g}, over the limit {limit_name}={limit}. "
            f"Try: {hint + '; or ' if hint else ''}raise it with {raise_hint(limit_name)}.")


_JSON_STRING = re.compile(rb'"[^"\\]*(?:\\.[^"\\]*)*"')     # a JSON string literal, escapes included
_BRACKET_STEP = np.zeros(256, dtype=np.int8)
_BRACKET_STEP[[ord("["), ord("{")]] = 1
_BRACKET_STEP[[ord("]"), ord("}")]] = -1


def json_text_depth(data: bytes, chunk: int = 2**20) -> int:
    """Deepest nesting of ``[ ]``/``{ }`` in JSON text: max over prefixes of (#open - #close),
    brackets inside string literals not counted. Runs in chunks, so memory stays O(chunk)."""
    steps = _BRACKET_STEP[np.frombuffer(_JSON_STRING.sub(b'""', data), dtype=np.uint8)]
    level, deepest = 0, 0
    for start in range(0, len(steps), chunk):
        levels = level + np.cumsum(steps[start:start + chunk], dtype=np.int64)
        deepest, level = max(deepest, int(levels.max())), int(levels[-1])
    return deepest


def check_json_depth(data: bytes, what: str, hint: str = "") -> None:
    """Raise ResourceLimitError if the JSON text ``data`` nests deeper than ``max_json_depth``
    (checked before parsing: Python's parser would otherwise hit its recursion limit)."""
    check_count(json_text_depth(data), "max_json_depth", f"the nesting depth of {what}", hint)
