"""The ``sosdyn`` command: fit, roll out, run experiments, build reports, list LASA shapes.

    sosdyn fit demo1.csv demo2.csv --out model.json [--components K ...]
    sosdyn fit lasa:Leaf_1 --out leaf.json
    sosdyn rollout model.json --from 10,-5 [--duration T --dt DT --out traj.csv]
    sosdyn export model.json --to python|cpp --out field.py|field.hpp   # standalone evaluator
    sosdyn plot model.json [--demos a.csv --demos b.csv | --demos lasa:NAME] --out fig.png|svg
    sosdyn experiment fig1 [--repo DIR] [--quick ...]   # python -m problems fig1, in DIR
    sosdyn report [--results reports/results.json --out reports]   # render a results file
    sosdyn lasa list

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
entries first. sosdyn itself and its solvers are imported inside the commands, so
``sosdyn --help`` is quick.
"""

from __future__ import annotations

import enum
import importlib
import logging
import sys
import time
from contextlib import nullcontext
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.console import Console
from rich.logging import RichHandler
from rich.markup import escape

from ..errors import InputError, SosdynError
from .paths import check_folder, check_output, existing

app = typer.Typer(name="sosdyn", no_args_is_help=True, add_completion=False,
                  help="SOS programming and provably convergent motion learning (CDSP).")
lasa_app = typer.Typer(no_args_is_help=True, help="The LASA handwriting data set.")
app.add_typer(lasa_app, name="lasa")

out = Console()
err = Console(stderr=True)


class _State:
    """Global options, set by the app callback."""

    quiet = False
    debug = False


class SolverMethod(str, enum.Enum):
    alternating = "alternating"
    ica = "ica"


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
    _State.quiet, _State.debug = quiet, debug
    if debug:
        logging.basicConfig(level=logging.DEBUG, format="%(message)s",
                            handlers=[RichHandler(console=err, show_path=True)])


def _info(message: str) -> None:
    if not _State.quiet:
        out.print(message)


def _status(message: str):
    """A spinner while a long single call runs (nothing when --quiet)."""
    return nullcontext() if _State.quiet else err.status(message)


def _positive(value: float | None) -> float | None:
    """Option callback: a finite number > 0 (or not given)."""
    if value is not None and not 0 < value < float("inf"):
        raise typer.BadParameter(f"must be a finite number > 0, got {value}.")
    return value


def _parse_point(text: str) -> np.ndarray:
    try:
        point = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise InputError(f"--from expects comma-separated numbers like 10,-5; got {text!r}.") from None
    if not np.all(np.isfinite(point)):
        raise InputError(f"--from must be finite; got {text!r}.")
    return point


# --------------------------------------------------------------------------- commands

@app.command()
def fit(
    demos: Annotated[list[str], typer.Argument(
        help="Demonstration files (CSV/NPY, one demonstration each), or lasa:NAME.", show_default=False)],
    out_path: Annotated[Path, typer.Option("--out", "-o", help="Where to save the model (JSON).")] = Path("model.json"),
    components: Annotated[int | None, typer.Option("--components", "-k", min=1, help="Gaussian components K.")] = None,
    metric_degree: Annotated[int | None, typer.Option(min=0, help="Degree of the polynomial metric.")] = None,
    field_degree: Annotated[int | None, typer.Option(min=1, help="Degree of the polynomial field.")] = None,
    gamma: Annotated[float | None, typer.Option(callback=_positive, help="Contraction rate (> 0).")] = None,
    solver: Annotated[str | None, typer.Option(help="Conic solver, e.g. CLARABEL or SCS.")] = None,
    solver_method: Annotated[SolverMethod | None, typer.Option(
        "--solver-method", "--method", help="How the bilinear program is solved (CDSP's solver_method).")] = None,
    seed: Annotated[int | None, typer.Option(min=0, max=2**32 - 1, help="Random seed (EM initialisation).")] = None,
) -> None:
    """Learn a certified CDSP model from demonstrations and save it.

    Options left out use the model's defaults.
    """
    import sosdyn as sd

    lasa = len(demos) == 1 and demos[0].startswith("lasa:")
    paths = [] if lasa else [existing(Path(p), "demonstration file") for p in demos]
    check_output(out_path, paths, "demonstration file")
    check_folder(out_path.parent)
    data = sd.load_lasa(demos[0].removeprefix("lasa:")) if lasa else sd.load_demos(paths)
    options = {"n_components": components, "metric_degree": metric_degree, "field_degree": field_degree,
               "gamma": gamma, "solver": solver, "solver_method": solver_method and solver_method.value,
               "random_state": seed}
    model = sd.CDSP(**{k: v for k, v in options.items() if v is not None})
    start = time.perf_counter()
    message = f"fitting CDSP to {len(data)} demonstrations of {data.name}"
    with _status(message + " ...") as status:
        if status is not None:
            model.progress = lambda row: status.update(
                f"{message}: step {row['iteration'] + 1} ({row['step']}), cost {row['cost']:.4g}")
        model.fit(data)
    model.progress = None
    model.save(out_path)
    report = model.verification_
    _info(f"[green]saved[/] {escape(str(out_path))}  ({len(data)} demonstrations, "
          f"fit in {time.perf_counter() - start:.1f} s, {len(model.history_)} convex steps)")
    _info(f"certificate: {'[green]passed[/]' if report.passed else '[red]FAILED[/]'} — min Gram eigenvalue "
          f"{report.min_gram_eig:.2e}, max sampled generalised eigenvalue {report.max_sampled_eig:.2e} "
          f"over {report.n_samples} states")


@app.command()
def rollout(
    model_path: Annotated[Path, typer.Argument(help="A model saved by `sosdyn fit`.", show_default=False)],
    start: Annotated[str, typer.Option("--from", help="Start state, comma-separated, e.g. 10,-5.",
                                       show_default=False)],
    duration: Annotated[float, typer.Option(callback=_positive, help="Seconds to integrate.")] = 10.0,
    dt: Annotated[float | None, typer.Option(callback=_positive, help="Time step (s); default: the model's.")] = None,
    out_path: Annotated[Path | None, typer.Option("--out", "-o", help="Write t and positions as CSV.")] = None,
) -> None:
    """Integrate a saved model from a start state; print the end point, optionally write
    a CSV (columns t,x1..xn: loadable again as a demonstration)."""
    import sosdyn as sd

    x0 = _parse_point(start)
    existing(model_path, "model file")
    if out_path is not None:
        check_output(out_path, [model_path], "model file")
        check_folder(out_path.parent)
    model = sd.load_model(model_path)
    traj = model.rollout(x0, duration, **({} if dt is None else {"dt": dt}))
    t, pos = np.asarray(traj.t), np.asarray(traj.pos)
    if out_path is not None:                     # the layout load_demos reads
        np.savetxt(out_path, np.column_stack([t, pos]), delimiter=",", comments="",
                   header=",".join(["t", *(f"x{i + 1}" for i in range(pos.shape[1]))]))
        _info(f"[green]wrote[/] {escape(str(out_path))}  ({len(t)} steps)")
    end = ", ".join(f"{v:.4g}" for v in pos[-1])
    out.print(f"t = {t[-1]:.3g} s: x = ({end})")


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
    """Render a results JSON into index.html and report.pdf (refused, and --out left
    untouched, unless it is a results file; figures must lie below the results file's folder).

    This only renders. `make report` (python -m problems report) rebuilds the results file and
    its figures from the cached experiment entries first."""
    from ..report.html import REPORT_FILES, build_report

    existing(results, "results file")
    check_folder(out_dir, create=True)
    for name in REPORT_FILES.values():
        check_output(out_dir / name, [results], "results file")
    with _status("rendering the report ..."):
        paths = build_report(results, out_dir)
    _info(f"[green]wrote[/] {escape(str(paths['html']))} and {escape(str(paths['pdf']))}")


class ExportTarget(str, enum.Enum):
    python = "python"
    cpp = "cpp"


@app.command("export")
def export_model(
    model_path: Annotated[Path, typer.Argument(help="A model saved by `sosdyn fit`.", show_default=False)],
    target: Annotated[ExportTarget, typer.Option("--to", help="python: one numpy-only module; cpp: a "
                                                "header-only C++17 evaluator.", show_default=False)],
    out_path: Annotated[Path, typer.Option("--out", "-o", help="The file to write (.py or .hpp).",
                                           show_default=False)],
) -> None:
    """Write a standalone evaluator of a saved model (no sosdyn needed to run it): Python
    `predict(X) -> Xdot` with numpy only, or C++17 `bool predict(const double* x, double* xdot)`."""
    import sosdyn as sd

    from ..lfd.export import export as generate
    from ..lfd.model_io import replace_atomically

    existing(model_path, "model file")
    check_output(out_path, [model_path], "model file")
    check_folder(out_path.parent)
    source = generate(sd.load_model(model_path), target.value)
    replace_atomically(out_path, source.encode("utf-8"))
    _info(f"[green]wrote[/] {escape(str(out_path))}  ({target.value}, {len(source.splitlines())} lines)")


PLOT_FORMATS = (".png", ".svg")


@app.command()
def plot(
    model_path: Annotated[Path, typer.Argument(help="A model saved by `sosdyn fit`.", show_default=False)],
    out_path: Annotated[Path, typer.Option("--out", "-o", help="The figure (.png or .svg).", show_default=False)],
    demos: Annotated[list[str] | None, typer.Option(
        "--demos", help="Demonstrations to draw (CSV/NPY files, or lasa:NAME); repeat the option for "
                        "several files. Reproductions start from their first states.", show_default=False)] = None,
    duration: Annotated[float | None, typer.Option(callback=_positive, help="Seconds per reproduction; "
                                                   "default: the demonstrations' longest (10 s without).")] = None,
) -> None:
    """Plot a saved model: streamlines (n = 2), 3-D trajectories (n = 3), or each dimension of
    the reproductions over time (n > 3). Without --demos the reproductions start at the
    mixture's means."""
    import matplotlib as mpl

    import sosdyn as sd

    from ..report.figures import STYLE, streamlines, time_series, trajectories_3d

    if out_path.suffix.lower() not in PLOT_FORMATS:
        raise InputError(f"--out {out_path} must end in .png or .svg. Try: --out {out_path.with_suffix('.png')}.")
    demos = demos or []
    lasa = len(demos) == 1 and demos[0].startswith("lasa:")
    paths = [] if lasa else [existing(Path(p), "demonstration file") for p in demos]
    existing(model_path, "model file")
    check_output(out_path, [model_path, *paths], "input")
    check_folder(out_path.parent)
    model = sd.load_model(model_path)
    data = (sd.load_lasa(demos[0].removeprefix("lasa:")) if lasa else sd.load_demos(paths)) if demos else None
    if data is not None and data.dim != model.dim_:
        raise InputError(f"the demonstrations are {data.dim}-D but the model is {model.dim_}-D. "
                         "Try: the demonstrations the model was fitted to.")
    demo_pos = [d.pos for d in data] if data is not None else []
    starts = [p[0] for p in demo_pos] or list(model.goal_ + model.scale_ * model.mixture_.means)
    horizon = duration or (max(float(d.t[-1] - d.t[0]) for d in data) if data is not None else 10.0)
    with _status(f"rolling out {len(starts)} reproductions ..."):
        runs = [model.rollout(x0, horizon) for x0 in starts]
    title = model_path.stem
    if model.dim_ == 2:
        fig = streamlines(None, model.predict, demo_pos, [r.pos for r in runs], model.goal_, title=title,
                          units=model.units_)
    elif model.dim_ == 3:
        fig = trajectories_3d(demo_pos, [r.pos for r in runs], model.goal_, title=title, units=model.units_)
    else:
        fig = time_series([(r.t, r.pos) for r in runs], model.goal_, model.units_, title)
    with mpl.rc_context(STYLE):
        fig.savefig(out_path, format=out_path.suffix.lower()[1:], dpi=150, metadata=_no_date(out_path))
    _info(f"[green]wrote[/] {escape(str(out_path))}  ({model.dim_}-D model, {len(runs)} reproductions)")


def _no_date(path: Path) -> dict:
    """savefig metadata: no creation date in an SVG, so equal inputs give equal files."""
    return {"Date": None} if path.suffix.lower() == ".svg" else {}


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
    (MemoryError, "smaller inputs; sosdyn.set_limits(max_bytes=...) bounds what is attempted."),
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


def main(argv: list[str] | None = None) -> None:
    """Run the CLI; the errors in ``_REPORTED`` become one line ``error: ...`` and exit 1
    (re-raised with --debug or SOSDYN_DEBUG=1)."""
    _State.debug = False
    try:
        app(args=argv, prog_name="sosdyn")
    except _REPORTED as exc:
        if _State.debug:
            raise
        err.print(f"[bold red]error:[/] {escape(error_line(exc))}", soft_wrap=True, highlight=False)
        raise SystemExit(1) from None
    except KeyboardInterrupt:
        err.print("[red]interrupted[/]")
        raise SystemExit(130) from None
