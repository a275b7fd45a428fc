"""Writing files atomically: a reader sees the old file or the new one, never half of one.

:func:`replace_atomically` writes the bytes to a temporary file beside the target, flushes and
fsyncs it, then renames it over the target (``os.replace``). The rename replaces the target's
directory entry, so a target that is a symlink is replaced by the new file and the symlink's
destination is never written; a write that fails (disk full, permission, an interrupt) removes
the temporary file, leaves the previous file intact and raises the OSError.
"""
from __future__ import annotations

import os
import secrets
from pathlib import Path


def replace_atomically(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to a temporary file beside ``path``, fsync it, rename it over ``path``."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{secrets.token_hex(6)}.tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), 0o666)   # umask applies
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    _sync_folder(path.parent)
    return path


def _sync_folder(folder: Path) -> None:
    """Make the rename durable (POSIX). The new file is already complete and in place, so a
    filesystem that cannot fsync a folder only loses that durability, not the file."""
    if os.name != "posix":
        return
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)
