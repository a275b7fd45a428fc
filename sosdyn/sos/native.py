"""A native solver's crash kept off the terminal: a Rust panic in Clarabel prints its message and
backtrace to file descriptor 2, past Python's ``sys.stderr``; callers redirect it here and turn
the crash into a status (:mod:`.backends`, :mod:`.kernel`)."""
from __future__ import annotations

import os
import sys
import tempfile
from contextlib import contextmanager


#: what a ``except BaseException`` around a native call re-raises: the user's or the interpreter's
#: stop, not a crash of the solver (a Rust panic arrives as a BaseException of its own)
INTERRUPTS = (KeyboardInterrupt, SystemExit, GeneratorExit)


class Captured:
    """The text a native library wrote to file descriptor 2 inside :func:`native_stderr`."""

    text: str = ""


@contextmanager
def native_stderr():
    """File descriptor 2 redirected into a temporary file for the duration (a Rust panic in
    Clarabel prints its message and backtrace there, past Python's sys.stderr); yields a
    :class:`Captured` whose ``text`` is set on exit."""
    out = Captured()
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError):          # no descriptor 2 (an embedded interpreter): nothing to hide
        yield out
        return
    with tempfile.TemporaryFile() as tmp:
        os.dup2(tmp.fileno(), 2)
        try:
            yield out
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            tmp.seek(0)
            out.text = tmp.read().decode(errors="replace")
