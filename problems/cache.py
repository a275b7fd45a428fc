"""The cache of fitted-and-scored entries: ``<cache>/<shape>__<method>.json``, keyed by the
method's settings and the evaluation config (a changed key refits)."""
from __future__ import annotations

import dataclasses
import hashlib
import json
from collections.abc import Sequence
from pathlib import Path

from .settings import CACHE, CACHE_VERSION, METHOD_ORDER, METHODS, EvalConfig, Shape, shape


def cache_key(shp: Shape, method: str, config: EvalConfig) -> dict:
    """What an entry depends on: shape settings, method settings, evaluation config."""
    return {"version": CACHE_VERSION, "shape": dataclasses.asdict(shp), "method": method,
            "settings": METHODS[method].settings(shp, config.quick), "config": config.key()}


def key_hash(key: dict) -> str:
    """First 16 hex digits of the SHA-256 of the key's canonical JSON."""
    return hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()[:16]


def cache_path(shp: Shape, method: str, config: EvalConfig, cache_dir: Path | None = None) -> Path:
    safe = "".join(c if c.isalnum() or c in "-_" else "_" for c in method)
    tag = f"__K{shp.K}" if shp != shape(shp.name) else ""
    quick = "__quick" if config.quick else ""
    return Path(cache_dir or CACHE) / f"{shp.name}{tag}__{safe}{quick}.json"


def read_cache(shp: Shape, method: str, config: EvalConfig, cache_dir: Path | None = None) -> dict | None:
    """The cached entry if its key matches ``(shape, method settings, config)``, else None."""
    path = cache_path(shp, method, config, cache_dir)
    try:
        entry = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return entry if entry.get("key_hash") == key_hash(cache_key(shp, method, config)) else None


def write_cache(entry: dict, shp: Shape, method: str, config: EvalConfig,
                cache_dir: Path | None = None) -> None:
    """Write a JSON-able entry atomically (temporary file, then rename)."""
    path = cache_path(shp, method, config, cache_dir)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(entry, allow_nan=True))
    tmp.replace(path)


def cached_entries(shapes: Sequence[Shape], methods: Sequence[str] = METHOD_ORDER, *,
                   config: EvalConfig | None = None, cache_dir: Path | None = None) -> dict:
    """Like :func:`problems.jobs.evaluate_all` but from the cache only (missing pairs are left out)."""
    config = config or EvalConfig()
    out = {}
    for s in shapes:
        for m in methods:
            entry = read_cache(s, m, config, cache_dir)
            if entry is not None:
                out.setdefault(s.name, {})[m] = entry
    return out
