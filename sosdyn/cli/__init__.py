"""The ``sosdyn`` command: fit, roll out, run experiments, build reports, list LASA shapes.

    sosdyn fit demo1.csv demo2.csv --out model.json [--components K ...]   # commands in .fit
    sosdyn fit demos/ --dt 0.01 --units m        # a folder (or 'demos/*.csv') of files without time
    sosdyn fit lasa:Leaf_1 --out leaf.json
    sosdyn fit logs/ --time-units ms --columns x,y,z    # ms stamps; position columns named
    sosdyn rollout model.json --start 10,-5 [--push T:DX,DY --goal-change T:X,Y --max-speed V
                   --duration T --dt DT --out traj.csv]
    sosdyn export model.json --to python|cpp [--max-speed V] --out field.py|field.hpp   # standalone,
                   # predict(X, goal=None) / predict(x, xdot, goal = nullptr): the goal moves at run time
    sosdyn plot model.json [--demos a.csv b.csv | --demos DIR | --demos lasa:NAME] --out fig.png|svg
    sosdyn experiment fig1 [--repo DIR] [--quick ...]   # python -m problems fig1, in DIR
    sosdyn report [--results reports/results.json --out reports]   # render a results file
    sosdyn lasa list
    sosdyn fit poses/ --out pose.json     # t,x,y,z,qw,qx,qy,qz CSVs: a pose model
    sosdyn fit crossing/ --order 2 --out o2.json  # a second-order model (follows crossing demonstrations)

Every command on a model (rollout, export, plot) takes any family's file: it goes through the model
interface (:class:`~sosdyn.lfd.model.base.MotionModel`) and never asks which family it holds.

Global options ``--quiet`` (no progress or summaries) and ``--debug`` (full
tracebacks, debug logging; also ``SOSDYN_DEBUG=1``) go before the command;
``sosdyn --version`` prints the version.

Every ``--out`` is checked before any work (:mod:`.paths`). Any sosdyn error, OS error, bad
value or over-deep input ends the command with one line ``error: ... Try: ...`` on stderr and
exit status 1; a malformed option is a usage error with exit status 2.

The experiments live in the repository's ``problems/`` folder, not in the package:
``sosdyn experiment`` finds them in ``--repo DIR``, by default in the source tree the
installed sosdyn comes from (an editable install), and says so when there is none.
``sosdyn report`` only renders an existing results file; ``make report`` (``python -m
problems report``) rebuilds the results file and the figures from the cached experiment
entries first. The commands on a model (rollout, export, plot) are in :mod:`.models`, what
they share in :mod:`.base`.
"""

from __future__ import annotations

import importlib
import logging
import sys
import warnings
from pathlib import Path
from typing import Annotated

import typer
from rich.logging import RichHandler
from rich.markup import escape

from ..errors import InputError, SosdynError
from ..limits import env_name
from . import fit, models  # noqa: F401 -- registers their commands on the app
from .base import State, app, err, info, lasa_app, out, status
from .paths import check_folder, check_output, existing


def _print_version(value: bool) -> None:
    """Option callback of --version: print ``sosdyn X.Y.Z`` and exit."""
    if value:
        from .. import __version__
        out.print(f"sosdyn {__version__}", highlight=False)
        raise typer.Exit()


@app.callback()
def _global_options(
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="Print results only: no progress, no summaries.")] = False,
    debug: Annotated[bool, typer.Option("--debug", envvar="SOSDYN_DEBUG",
                                        help="Show full tracebacks and debug logs.")] = False,
    version: Annotated[bool, typer.Option("--version", is_eager=True, callback=_print_version,
                                          help="Print the sosdyn version and exit.")] = False,
) -> None:
    State.quiet, State.debug = quiet, debug
    if debug:
        logging.basicConfig(level=logging.DEBUG, format="%(message)s",
                            handlers=[RichHandler(console=err, show_path=True)])


#: The source tree this sosdyn was imported from (the repository, for an editable install).
SOURCE_TREE = Path(__file__).resolve().parents[2]


def experiments_package(repo: Path | None = None):
    """The ``problems`` package of ``repo`` (default :data:`SOURCE_TREE`), imported from there.

    InputError when the folder holds no ``problems/`` (an installed, non-editable sosdyn has
    none) or when another ``problems`` package is already loaded.
    """
    root = (SOURCE_TREE if repo is None else Path(repo)).resolve()
    init = root / "problems" / "__init__.py"
    if not init.is_file():
        where = (f"this sosdyn is not installed from a source checkout ({root} has no problems/)"
                 if repo is None else f"{root} has no problems/ folder")
        raise InputError(f"no experiments found: {where}. Try: --repo DIR with DIR a clone of the "
                         "sosdyn repository (git clone, then pip install -e DIR).")
    loaded = sys.modules.get("problems")
    if loaded is None:
        sys.path.insert(0, str(root))
        loaded = importlib.import_module("problems")
    if Path(loaded.__file__ or "").resolve() != init:
        raise InputError(f"a different package named 'problems' is loaded ({loaded.__file__}), not {init}. "
                         "Try: run sosdyn experiment from another folder, or python -m problems in the repository.")
    return loaded


@app.command(context_settings={"allow_extra_args": True, "ignore_unknown_options": True})
def experiment(
    ctx: typer.Context,
    name: Annotated[str, typer.Argument(help="Experiment name, e.g. run, fig1, lasa-all, bench; options after "
                                             "it (--quick, --shapes ...) go to the experiment.", show_default=False)],
    repo: Annotated[Path | None, typer.Option(
        help="The sosdyn repository whose problems/ holds the experiments; default: the source tree of "
             "this sosdyn (editable install).", show_default=False)] = None,
) -> None:
    """Run one experiment of the repository's problems/ (same as `python -m problems NAME`)."""
    code = experiments_package(repo).run_experiment(name, ctx.args)
    if code:
        raise typer.Exit(code)


@app.command()
def report(
    results: Annotated[Path, typer.Option(help="Results JSON written by the experiments.")] = Path("reports/results.json"),
    out_dir: Annotated[Path, typer.Option("--out", "-o", help="Folder for index.html and report.pdf.")] = Path("reports"),
) -> None:
    """Render a results JSON into index.html and report.pdf (the user report).

    Refused, and --out left untouched, unless it is a results file; figures must lie below the
    results file's folder.

    This only renders. `make report` (python -m problems report) rebuilds the results file and
    its figures from the cached experiment entries first."""
    from ..report.html import REPORT_FILES, build_report

    existing(results, "results file")
    check_folder(out_dir, create=True)
    for name in REPORT_FILES.values():
        check_output(out_dir / name, [results], "results file")
    with status("rendering the report ..."):
        paths = build_report(results, out_dir)
    info(f"[green]wrote[/] {escape(str(paths['html']))} and {escape(str(paths['pdf']))}")


@lasa_app.command("list")
def lasa_list() -> None:
    """Print the names of the 30 LASA shapes, one per line."""
    import sosdyn as sd

    for name in sd.lasa_names():
        out.print(name, highlight=False)


# ------------------------------------------------------------------------ entry point

# Errors reported as one line (anything else is a bug and keeps its traceback), and what
# to try for those whose message does not say (first matching class wins).
_REPORTED = (SosdynError, OSError, ValueError, RecursionError, MemoryError)
_HINTS = (
    (PermissionError, "check the permissions, or choose another path."),
    (OSError, "check the path."),
    (RecursionError, "check that the file is one sosdyn wrote (its nesting is too deep to read)."),
    (MemoryError, f"smaller inputs; or a lower {env_name('max_bytes')} in the environment: sosdyn estimates its "
                  "large allocations first and refuses work estimated over that limit before it starts."),
    (SosdynError, "rerun with --debug for details."),
    (ValueError, "check the options (sosdyn COMMAND --help); rerun with --debug for the traceback."),
)


def error_line(exc: BaseException) -> str:
    """The one-line report of ``exc``: its message's lines joined ("; " after a line without
    closing punctuation) and, when the message has none, a "Try: ..." hint by class."""
    if isinstance(exc, OSError) and exc.strerror:
        names = [str(f) for f in (exc.filename, exc.filename2) if f is not None]
        text = f"{exc.strerror}: {' -> '.join(names)}" if names else exc.strerror
    else:
        text = str(exc) or {MemoryError: "out of memory"}.get(type(exc), type(exc).__name__)
    if isinstance(exc, RecursionError):
        text = f"input nested too deeply ({text})"
    lines = [line.strip() for line in text.splitlines() if line.strip()] or [type(exc).__name__]
    text = "".join(line + (" " if line[-1] in ".:;,!?" else "; ") for line in lines[:-1]) + lines[-1]
    if "Try:" not in text:
        hint = next(h for cls, h in _HINTS if isinstance(exc, cls))
        text = f"{text.rstrip('.')}. Try: {hint}"
    return text


def show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """A Python warning raised while a command runs, as one line: ``note: ...`` for a UserWarning (what
    the loaders announce, e.g. repeated time stamps merged), ``warning: ...`` for anything else
    (nothing with --quiet); the source line only with --debug."""
    if State.debug:
        err.print(warnings.formatwarning(message, category, filename, lineno, line), highlight=False, markup=False)
    elif issubclass(category, UserWarning) and not issubclass(category, RuntimeWarning):
        info(f"note: {escape(str(message))}")
    elif not State.quiet:
        err.print(f"[yellow]warning:[/] {escape(f'{category.__name__}: {message}')}", soft_wrap=True, highlight=False)


def main(argv: list[str] | None = None) -> None:
    """Run the CLI; the errors in ``_REPORTED`` become one line ``error: ...`` and exit 1
    (re-raised with --debug or SOSDYN_DEBUG=1)."""
    State.debug = False
    try:
        with warnings.catch_warnings():
            warnings.showwarning = show_warning
            app(args=argv, prog_name="sosdyn")
    except _REPORTED as exc:
        if State.debug:
            raise
        err.print(f"[bold red]error:[/] {escape(error_line(exc))}", soft_wrap=True, highlight=False)
        raise SystemExit(1) from None
    except KeyboardInterrupt:
        err.print("[red]interrupted[/]")
        raise SystemExit(130) from None
