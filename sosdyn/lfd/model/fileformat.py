"""Model files: plain JSON (no pickle), checksummed, optionally signed, written atomically.

This module knows the file, not the estimator: its content is a dict whose ``state`` is
checked field by field by :mod:`sosdyn.lfd.model.content`. A file is one JSON object::

    format       "sosdyn-cdsp"
    version      2
    params       the hyper-parameters
    state        the learned values; arrays as nested lists of floats (exact under JSON round trips)
    sha256       SHA-256 of canonical(every other field)
    hmac_sha256  optional: HMAC-SHA256 of the same bytes under a secret key

``canonical`` is the JSON text with sorted keys, no whitespace, ASCII only and no NaN/inf, so
the digest covers every byte of content that matters (goal, scale, dt, units, mixture,
coefficients, certificate, parameters, diagnostics), whatever the file's layout.

What the checksum does NOT do: it detects accidental corruption (a truncated copy, a flipped
bit, an edit that did not recompute it) and nothing more. Anyone can edit a file and recompute
the SHA-256. Against deliberate edits, sign the file with a secret key: ``save(path, key=...)``
writes the HMAC, ``load_model(path, key=...)`` requires it and refuses a file without it or
with a wrong one; the environment variable ``SOSDYN_MODEL_KEY`` is the default key of both.

Reading is bounded: regular files only (after resolving symlinks: no devices, FIFOs or
directories), at most ``max_file_bytes`` bytes read, nesting at most ``max_json_depth``
(:mod:`sosdyn.limits`), no duplicate keys, only finite numbers. Every failure is a
:class:`~sosdyn.errors.ModelFileError` saying what was wrong and what to try.

Writing is atomic: the text goes to a temporary file in the same folder, is flushed and
fsync'ed, then renamed over the target (``os.replace``); a save that fails part-way leaves the
previous file intact, and a reader never sees a half-written file.
"""
from __future__ import annotations

import hashlib
import hmac
import json
import math
import os
import stat
from pathlib import Path

import numpy as np

from sosdyn.errors import InputError, ModelFileError, ResourceLimitError
from sosdyn.files import replace_atomically as write_atomically
from sosdyn.limits import check_json_depth, format_bytes, get_limits, raise_hint

FORMAT, VERSION = "sosdyn-cdsp", 2
CHECKSUM, SIGNATURE = "sha256", "hmac_sha256"
KEY_ENV = "SOSDYN_MODEL_KEY"
REFIT_HINT = "Try: refit the model and save it again (or restore the file from where it came from)."


# ---------------------------------------------------------------------- content and digests
def plain(obj):
    """``obj`` as JSON data: arrays and numpy scalars to lists and Python numbers."""
    if isinstance(obj, dict):
        return {k: plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [plain(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


def canonical(content: dict) -> bytes:
    """The bytes the checksum and the signature cover: every field except the two digests."""
    body = {k: v for k, v in content.items() if k not in (CHECKSUM, SIGNATURE)}
    return json.dumps(body, sort_keys=True, separators=(",", ":"), ensure_ascii=True,
                      allow_nan=False).encode("ascii")


def _digest(content: dict) -> str:
    return hashlib.sha256(canonical(content)).hexdigest()


def _signature(content: dict, key: bytes) -> str:
    return hmac.new(key, canonical(content), hashlib.sha256).hexdigest()


def resolve_key(key) -> bytes | None:
    """The signing key: ``key`` (bytes or str), else $SOSDYN_MODEL_KEY, else None (no signature)."""
    if key is None:
        key = os.environ.get(KEY_ENV) or None
        if key is None:
            return None
    if isinstance(key, str):
        key = key.encode("utf-8")
    if not isinstance(key, (bytes, bytearray)) or not key:
        raise InputError(f"key must be non-empty bytes or str, got {type(key).__name__} {key!r:.40}. "
                         f"Try: key=b'...' (a secret of 32 random bytes, e.g. os.urandom(32)), "
                         f"or set {KEY_ENV}.")
    return bytes(key)


def first_bad_value(obj, where: str = "") -> tuple[str, str] | None:
    """(field, what) of the first value that is not finite JSON data, or None.

    Fields are named like ``state.C_[0][1][2]``; iterative, so depth cannot overflow the stack.
    """
    stack = [(where, obj)]
    while stack:
        w, v = stack.pop()
        if isinstance(v, dict):
            for k in reversed(list(v)):
                if not isinstance(k, str):
                    return w, f"a key {k!r} that is not a string"
                stack.append((f"{w}.{k}" if w else k, v[k]))
        elif isinstance(v, list):
            stack.extend((f"{w}[{i}]", x) for i, x in reversed(list(enumerate(v))))
        elif isinstance(v, float):
            if not math.isfinite(v):
                return w, repr(v)
        elif not (v is None or isinstance(v, (str, int))):
            return w, f"a {type(v).__name__}, not JSON data"
    return None


# ---------------------------------------------------------------------- writing
def write_model_file(content: dict, path, key=None) -> Path:
    """Write ``content`` (format, version, params, state) with its checksum, and its HMAC when a
    key is given (or set in $SOSDYN_MODEL_KEY), atomically."""
    key = resolve_key(key)
    path = Path(path)
    content = plain(content)
    bad = first_bad_value(content)
    if bad is not None:
        raise ModelFileError(f"cannot save the model to {path}: {bad[0]} is {bad[1]}; a model file "
                             "holds finite numbers only. Try: save only models with certified_ = True "
                             "(an uncertified fit can leave NaN in its certificate).")
    doc = dict(content, **{CHECKSUM: _digest(content)})
    if key is not None:
        doc[SIGNATURE] = _signature(content, key)
    data = (json.dumps(doc, sort_keys=True, indent=1, allow_nan=False) + "\n").encode("utf-8")
    replace_atomically(path, data)
    return path


def replace_atomically(path: Path, data: bytes) -> None:
    """:func:`sosdyn.files.replace_atomically`, its OSError as a ModelFileError."""
    try:
        write_atomically(path, data)
    except OSError as exc:
        raise ModelFileError(f"could not write the model file {path}: {exc.strerror or exc}; the previous "
                             "file there, if any, is unchanged. Try: a folder that exists and is "
                             "writable, with free space.") from exc


# ---------------------------------------------------------------------- reading
_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
          (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISSOCK, "a socket"))


def _not_regular(path: Path, mode: int) -> ModelFileError:
    kind = next((name for test, name in _KINDS if test(mode)), "not a regular file")
    return ModelFileError(f"{path} is {kind} (after resolving symlinks), not a model file; a model "
                          "file is a regular JSON file written by save(). Try: the path of that file.")


def _too_big(path: Path, size: str, cap: int) -> ModelFileError:
    return ModelFileError(f"{path} is {size}, over the limit max_file_bytes = {format_bytes(cap)} for a "
                          "model file. Try: check it is the right file; if it is, raise the limit with "
                          f"{raise_hint('max_file_bytes')}.")


def read_bytes_capped(path: Path) -> bytes:
    """The bytes of a regular file, refusing anything else and anything over ``max_file_bytes``."""
    cap = get_limits().max_file_bytes
    try:
        st = os.stat(path)                          # follows symlinks: judge what they point to
        if not stat.S_ISREG(st.st_mode):
            raise _not_regular(path, st.st_mode)
        if st.st_size > cap:
            raise _too_big(path, format_bytes(st.st_size), cap)
        # O_NONBLOCK: if the path was swapped for a FIFO since stat, open must not hang
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
        with os.fdopen(fd, "rb") as f:
            mode = os.fstat(f.fileno()).st_mode
            if not stat.S_ISREG(mode):
                raise _not_regular(path, mode)
            data = f.read(cap + 1)
    except FileNotFoundError:
        raise ModelFileError(f"no model file at {path}. Try: the path printed by `sosdyn fit` or "
                             "passed to save().") from None
    except OSError as exc:
        raise ModelFileError(f"cannot read the model file {path}: {exc.strerror or exc}. "
                             "Try: check its permissions.") from None
    except ValueError as exc:                       # e.g. a NUL byte in the path
        raise ModelFileError(f"{str(path)!r} is not a usable path ({exc}). Try: the path of the "
                             "model file.") from None
    if len(data) > cap:
        raise _too_big(path, f"over {format_bytes(cap)} (it grew while being read)", cap)
    return data


def _unique_keys(pairs):
    out = dict(pairs)
    if len(out) != len(pairs):
        seen = set()
        dup = next(k for k, _ in pairs if k in seen or seen.add(k))
        raise ModelFileError(f"the key {dup!r} appears twice in one object, so the content is ambiguous")
    return out


def parse_json(data: bytes, path: Path):
    """Parse ``data`` strictly; nesting over ``max_json_depth`` is refused before parsing."""
    try:
        check_json_depth(data, "its JSON text", "check it is the right file")
    except ResourceLimitError as exc:
        raise ModelFileError(f"{path} is not a model file (one nests about 7 levels): {exc}") from None
    try:
        return json.loads(data.decode("utf-8"), object_pairs_hook=_unique_keys)
    except ModelFileError as exc:
        raise ModelFileError(f"{path} is not a valid model file: {exc}. {REFIT_HINT}") from None
    except RecursionError:                  # only with max_json_depth raised past Python's own limit
        raise ModelFileError(f"{path} nests JSON deeper than Python's parser allows (the limit "
                             f"max_json_depth is {get_limits().max_json_depth}); not a model file. "
                             f"{REFIT_HINT}") from None
    except (UnicodeDecodeError, ValueError) as exc:       # JSONDecodeError is a ValueError
        raise ModelFileError(f"{path} is not a sosdyn model file (corrupt or truncated JSON: {exc}). "
                             f"{REFIT_HINT}") from None


def model_format(path):
    """The ``format`` field of the JSON file at ``path`` (None when there is none), read with the
    same size, type and depth checks as :func:`read_model_file`: what the loaders dispatch on."""
    doc = parse_json(read_bytes_capped(Path(path)), Path(path))
    return doc.get("format") if isinstance(doc, dict) else None


def read_model_file(path, key=None, fmt: str = FORMAT, fmt_version: int = VERSION) -> dict:
    """The content (format, version, params, state) of a model file, after every check that
    does not need the estimator: size, type, JSON, format ``fmt`` and version ``fmt_version``, finite
    numbers, the checksum, and the signature when a key is given (or set in $SOSDYN_MODEL_KEY)."""
    key = resolve_key(key)
    path = Path(path)
    doc = parse_json(read_bytes_capped(path), path)
    if not isinstance(doc, dict) or doc.get("format") != fmt:
        raise ModelFileError(f"{path} is not a {fmt} file (no \"format\": \"{fmt}\" field). "
                             "Try: the JSON written by " + ("CDSP.save or `sosdyn fit`." if fmt == FORMAT
                                                            else "the model's save()."))
    version = doc.get("version")
    if version != fmt_version:
        if isinstance(version, int) and not isinstance(version, bool) and version < fmt_version:
            advice = "it was written by an older sosdyn. Try: refit the model and save it again."
        else:
            advice = "Try: a newer sosdyn, or refit the model with this one."
        raise ModelFileError(f"{path} has format version {version!r}; this sosdyn reads version "
                             f"{fmt_version} only: {advice}")
    bad = first_bad_value(doc)
    if bad is not None:
        raise ModelFileError(f"{path}: the field {bad[0]} is {bad[1]}; a model file holds finite "
                             f"numbers only. {REFIT_HINT}")
    if not isinstance(doc.get(CHECKSUM), str) or not hmac.compare_digest(doc[CHECKSUM], _digest(doc)):
        raise ModelFileError(f"{path} fails its checksum: the file was edited or corrupted. {REFIT_HINT}")
    if key is not None:
        sig = doc.get(SIGNATURE)
        if not isinstance(sig, str):
            raise ModelFileError(f"{path} is not signed, but a key was given (argument or {KEY_ENV}); "
                                 "an unsigned file cannot prove where it came from. Try: save it with "
                                 "save(path, key=...), or load it without a key if you trust it.")
        if not hmac.compare_digest(sig, _signature(doc, key)):
            raise ModelFileError(f"{path} fails its signature check: it was edited after signing, or "
                                 "signed with another key. Try: the key it was saved with; otherwise do "
                                 "not trust this file.")
    return {k: v for k, v in doc.items() if k not in (CHECKSUM, SIGNATURE)}
