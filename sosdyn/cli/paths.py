"""Where the ``sosdyn`` command may read and write: every ``--out`` is checked before any work.

An output is refused when it is a folder, read-only, in a folder that does not exist or is not
writable, or the same file as one of the command's inputs (same resolved path or same inode,
so symlinks and hard links count): writing it would destroy the input.
"""
from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

from ..errors import InputError


def existing(path: Path, what: str) -> Path:
    """``path``, or FileNotFoundError naming ``what`` (checked before sosdyn is asked)."""
    if path.is_dir():
        raise InputError(f"{what} {path} is a folder. Try: give the file inside it.")
    if not path.is_file():
        raise FileNotFoundError(f"{what} not found: {path}")
    return path


def same_file(a: Path, b: Path) -> bool:
    """Do ``a`` and ``b`` name one file: equal after resolving symlinks, or (both existing)
    the same inode, as for hard links."""
    try:
        return a.resolve() == b.resolve() or os.path.samefile(a, b)
    except (OSError, RuntimeError):   # one of them does not exist, or a symlink loop
        return False


def check_output(path: Path, inputs: Sequence[Path] = (), what: str = "input") -> None:
    """InputError unless ``path`` may be (over)written: not a folder, writable if it exists,
    and not the same file as any of ``inputs`` (each described as ``what``)."""
    if path.is_dir():
        raise InputError(f"--out {path} is a folder. Try: give a file path inside it.")
    for source in inputs:
        if same_file(path, source):
            raise InputError(f"--out {path} is the {what} {source}: writing it would destroy the input. "
                             "Try: choose another --out.")
    if path.exists() and not os.access(path, os.W_OK):
        raise InputError(f"--out {path} exists and is read-only. Try: choose another --out.")


def check_folder(folder: Path, *, create: bool = False) -> None:
    """InputError unless files can be written in ``folder``; with ``create`` it may also be
    a new folder whose parent exists and is writable."""
    target = folder
    if not folder.is_dir():
        if folder.exists():
            raise InputError(f"{folder} is a file, not a folder. Try: choose another --out.")
        if not (create and folder.parent.is_dir()):
            raise InputError(f"the folder {folder} does not exist. Try: create it (mkdir -p {folder}) "
                             "or choose another --out.")
        target = folder.parent
    if not os.access(target, os.W_OK | os.X_OK):
        raise InputError(f"cannot write in the folder {target} (permission denied). Try: choose another --out.")


DEMO_SUFFIXES = (".csv", ".npy")
#: Inputs that name a shipped set instead of files: read alone, one set per command.
LASA_PREFIX, DATASET_PREFIX = "lasa:", "dataset:"
_GLOB_CHARS = frozenset("*?[")


def _visible(path: Path) -> bool:
    """Not a dotfile (``.x.csv``, macOS's ``._x.csv`` resource forks, editors' ``.#x.csv``)."""
    return not path.name.startswith(".")


def demo_inputs(specs: Sequence[str]) -> list[Path]:
    """The demonstration files that ``specs`` name, in order, each once: a name that exists as it
    is, a file (``run[1].csv`` is that file, never a pattern) or a folder (its ``*.csv`` and ``*.npy``
    files, sorted by name, not recursive, dotfiles skipped); otherwise a pattern with ``*``, ``?`` or
    ``[`` as its matching files (sorted, dotfiles skipped unless the pattern's name starts with a dot;
    quote it so the shell leaves it alone). FileNotFoundError / InputError when a spec names nothing, and
    InputError for ``lasa:NAME`` / ``dataset:NAME`` among other inputs (a shipped set is read alone)."""
    files: list[Path] = []
    for spec in specs:
        path = Path(spec)
        if spec.startswith((LASA_PREFIX, DATASET_PREFIX)) and not path.exists():
            raise InputError(f"{spec} names a shipped set, and a shipped set is read alone: it cannot be mixed "
                             f"with other inputs ({', '.join(s for s in specs if s != spec)[:120]}). Try: "
                             f"sosdyn fit {spec} on its own, or only files and folders.")
        if path.is_dir():
            found = sorted(p for p in path.iterdir()
                           if p.suffix.lower() in DEMO_SUFFIXES and _visible(p) and p.is_file())
            if not found:
                raise InputError(f"the folder {path} holds no .csv or .npy file. Try: the folder of the "
                                 "demonstration files, or the files themselves.")
        elif path.exists() or not _GLOB_CHARS & set(spec):
            found = [existing(path, "demonstration file")]
        else:
            anchor = Path(path.anchor) if path.is_absolute() else Path()
            found = sorted(p for p in anchor.glob(str(path.relative_to(anchor)))
                           if p.is_file() and (_visible(p) or path.name.startswith(".")))
            if not found:
                raise InputError(f"no file matches {spec}. Try: check the pattern (e.g. 'demos/*.csv').")
        files.extend(p for p in found if not any(same_file(p, q) for q in files))
    return files
