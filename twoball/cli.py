"""The ``twoball`` command line: every command's arguments, checks and printing, in one place.

The modules of the library compute (:func:`twoball.simulate`, :mod:`twoball.batch.sweep`, the
studies in :mod:`twoball.studies`); this module only parses, checks ranges and prints. A command's
module is imported when the command runs, so that a command whose extra is not installed says which
one, and the others work without it.

Bad input never shows a traceback: a :class:`~twoball.errors.ParameterError` (or argparse's own
complaint) prints one line on stderr and exits with status 2, as does a path that cannot be read
or written. A run that is no answer (a :class:`~twoball.errors.SolverError`: stuck root finder,
phase limit) prints one line and exits with status 1. Any other exception is a bug and keeps its
traceback.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from collections.abc import Callable

from twoball.batch.sweep import DIMS as SWEEP_AXES
from twoball.batch.sweep import FORCES as SWEEP_FORCES
from twoball.batch.sweep import MAX_DROPS as MAX_SWEEP_DROPS
from twoball.batch.sweep import MAX_HERTZ_DROPS, parse_number
from twoball.errors import ParameterError, SolverError, Status
from twoball.model import DEFAULT_HEIGHT, Parameters, allowed_range

# The optional dependencies, by the extra that installs them (pyproject.toml).
EXTRAS = {
    "xarray": "sweep",
    "zarr": "sweep",
    "dask": "sweep",
    "distributed": "sweep",
    "tqdm": "sweep",
    "matplotlib": "studies",
    "mpmath": "studies",
    "sksundae": "cvode",
    "panel": "app",
    "holoviews": "app",
    "bokeh": "app",
}


class UsageError(ParameterError):
    """Bad input on the command line: reported in one line, exit status 2."""


class _Parser(argparse.ArgumentParser):
    _given: tuple[str, ...] = ()  # the arguments this parser was handed

    def parse_known_args(self, args=None, namespace=None):
        self._given = tuple(sys.argv[1:] if args is None else args)
        return super().parse_known_args(args, namespace)

    def error(self, message: str) -> None:  # argparse's own errors: one line, status 2
        unknown = self._unknown_options()
        if unknown and not message.startswith("unrecognized"):
            # (argparse names the required options missing first: a new user's misspelt or
            # unknown option was then never named)
            message = f"unrecognized arguments: {' '.join(unknown)}; {message}"
        raise UsageError(message)

    def _unknown_options(self) -> list[str]:
        """The options given that this parser does not know (nor any of its options begins
        with, as argparse takes abbreviations)."""
        known = list(self._option_string_actions)
        unknown = []
        for given in self._given:
            if given == "--":
                break
            name = given.split("=", 1)[0]
            option = given.startswith("-") and not _is_number(given)
            if option and not any(known_option.startswith(name) for known_option in known):
                unknown.append(name)
        return unknown


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


# Argument types: a number out of range is argparse's error, naming the option and the range.


def _number(text: str) -> float:
    """A number or a fraction such as 1/3 (:func:`twoball.batch.sweep.parse_number`), for
    argparse."""
    try:
        return parse_number(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def _integer_in(low: int, high: int) -> Callable[[str], int]:
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"must be from {low:,} to {high:,}; got {value:,}")
        return value

    return parse


def _seconds(text: str) -> float:
    value = _number(text)
    if not (math.isfinite(value) and 0 < value <= 86_400):
        raise argparse.ArgumentTypeError(f"seconds in (0, 86400]; got {text!r}")
    return value


def _path(text: str) -> str:
    """A file or directory name (the operating system refuses a NUL character in one)."""
    if "\0" in text:
        raise argparse.ArgumentTypeError(f"a path cannot contain a NUL character: {text!r}")
    return text


def _until(text: str) -> str | float:
    """``--until``: "first", "second" or a number (argparse reports anything else)."""
    if text in ("first", "second"):
        return text
    try:
        return parse_number(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"takes first, second or a time (a number > 0); got {text!r}"
        ) from None


def _store(text: str) -> str:
    """A sweep's store: a directory with a name of its own (not ".", "..", "" or "/", which
    name the directory the store would sit in, not the store)."""
    text = _path(text)
    if os.path.basename(os.path.normpath(text)) in ("", ".", "..", os.sep):
        raise argparse.ArgumentTypeError(
            f"must name the store's own directory, such as cube.zarr; got {text!r}"
        )
    # the store is made, not the directories above it: a mistyped path made them silently
    parent = os.path.dirname(os.path.normpath(os.path.abspath(text)))
    if not os.path.isdir(parent):
        why = "is not a directory" if os.path.exists(parent) else "does not exist (make it first)"
        raise argparse.ArgumentTypeError(f"{text}: the directory it goes in, {parent}, {why}")
    return text


_WORKERS = _integer_in(1, 1024)


# simulate


def _add_height(parser: argparse.ArgumentParser) -> None:
    """``--height`` of one drop or stack, its allowed range in the help (simulate, stack)."""
    parser.add_argument(
        "--height",
        type=_number,
        default=DEFAULT_HEIGHT,
        help=f"dimensionless drop height H in {allowed_range('height')}, within the domain "
        f"double precision carries (docs/model.md); default {DEFAULT_HEIGHT:g}",
    )


def _add_simulate(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("simulate", help="simulate one drop and print its bounces")
    parser.add_argument(
        "--eps", type=_number, required=True, help=f"restitution eps in {allowed_range('eps')}"
    )
    parser.add_argument(
        "--mu", type=_number, required=True, help=f"mass ratio m2/m1 in {allowed_range('mu')}"
    )
    parser.add_argument(
        "--tau-ratio",
        type=_number,
        required=True,
        help=f"tau_d/tau_f in {allowed_range('tau_ratio')}",
    )
    parser.add_argument(
        "--eps12",
        type=_number,
        default=None,
        help=f"ball-ball restitution in {allowed_range('eps12')} (default: eps)",
    )
    _add_height(parser)
    parser.add_argument(
        "--method", default="exact", help="exact, LSODA, Radau, BDF, DOP853, RK45, odeint or CVODE"
    )
    parser.add_argument(
        "--until", type=_until, default="second", help="first, second (apex) or a time"
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.set_defaults(func=_simulate)


def _simulate(args: argparse.Namespace) -> int:
    from twoball.model import check_parameters
    from twoball.solve import simulate

    check_parameters(args.eps, args.mu, args.tau_ratio, eps12=args.eps12, height=args.height)
    say_if_compiling(args)
    result = simulate(
        args.eps,
        args.mu,
        args.tau_ratio,
        eps12=args.eps12,
        height=args.height,
        until=args.until,
        method=args.method,
    )
    summary = result.summary()
    if summary["reason"] is None:
        summary["reason"] = _missing_apexes(args.until, len(result.apex_h), "upper ball")
    return _print_summary(summary, args.json)


def _missing_apexes(until: str | float, found: int, ball: str) -> str | None:
    """Why a run to a time shows fewer apexes than asked (rather than bare dashes), or None."""
    if isinstance(until, str) or found >= 2:  # ran to an apex, or found both
        return None
    which = "apex" if found == 0 else "second apex"
    return f"no {which} of the {ball} before t = {until:g} (--until)"


def _print_summary(summary: dict, as_json: bool) -> int:
    """A run's observables: one JSON object, or a column of names and values ("-" for none)."""
    if as_json:  # strict JSON: a number that is not one (nan, inf) is null, as none is
        print(json.dumps(_json_numbers(summary), allow_nan=False))
        return 0
    width = max(len(key) for key in summary)
    for key, value in summary.items():
        values = value if isinstance(value, list) else [value]
        shown = " ".join(
            "-" if v is None else f"{v:.12g}" if isinstance(v, float) else str(v) for v in values
        )
        print(f"{key:<{width}}  {shown}")
    return 0


def _json_numbers(value: object) -> object:
    """``value`` with every float that JSON cannot carry (nan, inf) as None."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {key: _json_numbers(item) for key, item in value.items()}
    if isinstance(value, list):
        return [_json_numbers(item) for item in value]
    return value


# stack


def _numbers(text: str) -> list[float]:
    """Comma-separated numbers (each as :func:`_number`), for argparse."""
    return [_number(part.strip()) for part in text.split(",")]


def _one_or_all(values: list[float]) -> float | list[float]:
    """A list option of ``stack``: one value given stands for every ball or pair (the library
    takes a number so, and refuses a list of the wrong length)."""
    return values[0] if len(values) == 1 else values


def _add_stack(subparsers: argparse._SubParsersAction) -> None:
    from twoball.stacks.model import (
        HERTZ_LARGEST_MASS,
        HERTZ_SMALLEST_RESTITUTION,
        SMALLEST_GAP,
        TOUCHING_LIMIT_BALLS,
    )

    parser = subparsers.add_parser(
        "stack", help="drop a stack of N balls and print the top ball's bounces"
    )
    parser.add_argument(
        "--mass-ratios",
        type=_numbers,
        required=True,
        help="m_i/m_(i-1) bottom up, comma-separated: N-1 values for N balls, each and their "
        f"products in {allowed_range('mu')} (hertz: products up to {HERTZ_LARGEST_MASS:g})",
    )
    parser.add_argument(
        "--eps",
        type=_numbers,
        default=[0.9],
        help=f"one restitution in {allowed_range('eps')}, or N: floor first (hertz: from "
        f"{HERTZ_SMALLEST_RESTITUTION:g})",
    )
    parser.add_argument(
        "--tau-ratios",
        type=_numbers,
        default=[0.2],
        help=f"one gap tau_d/tau_f in {allowed_range('tau_ratio')} (linear, with "
        f"{TOUCHING_LIMIT_BALLS} or more balls: from {SMALLEST_GAP:g}), or N-1 (0.2)",
    )
    _add_height(parser)
    parser.add_argument("--force", default="linear", help="linear (exact) or hertz")
    parser.add_argument(
        "--method",
        default="compiled",
        help="with --force hertz: compiled (default) or DOP853 (scipy's, the reference); the "
        "linear force has one, compiled (the exact solver: 'method compiled' in its output), and "
        "refuses any other",
    )
    parser.add_argument("--until", type=_until, default="second", help="first, second or a time")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.set_defaults(func=_stack)


def _stack(args: argparse.Namespace) -> int:
    from twoball.stacks import check_stack, simulate_stack
    from twoball.stacks.stack import solver_for

    eps, gaps = _one_or_all(args.eps), _one_or_all(args.tau_ratios)
    check_stack(args.mass_ratios, eps, gaps, height=args.height, force=args.force)
    solver_for(args.force, args.method)
    say_if_compiling(args)
    result = simulate_stack(
        args.mass_ratios,
        eps,
        gaps,
        height=args.height,
        force=args.force,
        until=args.until,
        method=args.method,
    )
    summary = result.summary()
    top_apexes = len(result.apexes[-1])
    reason = _missing_apexes(args.until, top_apexes, "top ball")
    if reason is not None or result.status is Status.REST:
        summary["reason"] = reason or "the stack came to rest"
    elif summary["reason"] is None and not args.json:
        del summary["reason"]  # a run that reached what was asked says nothing more (JSON: null)
    return _print_summary(summary, args.json)


# bench


def _add_bench(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("bench", help="time the exact solver against LSODA (odeint)")
    parser.add_argument(
        "--cases", type=_integer_in(1, 100_000), default=50, help="random cases (default 50)"
    )
    parser.add_argument(
        "--seed", type=_integer_in(0, 2**63 - 1), default=0, help="random seed (default 0)"
    )
    parser.add_argument(
        "--repeats", type=_integer_in(1, 1000), default=5, help="timed repeats per case"
    )
    parser.set_defaults(func=_bench)


def _bench(args: argparse.Namespace) -> int:
    from twoball.studies.bench import benchmark

    figures = benchmark(args.cases, args.seed, args.repeats)
    print(f"{args.cases} random cases of the paper's cube, H = 1e4, to the second apex")
    print(f"exact solver      median {figures['exact_median_s'] * 1e3:9.3f} ms per case")
    print(
        f"LSODA (odeint)    median {figures['lsoda_median_s'] * 1e3:9.3f} ms per case "
        "(rtol = atol = 1e-8, grid step 0.01)"
    )
    print(
        f"speed-up          median {figures['speedup_median']:9.1f} x, "
        f"slowest case {figures['speedup_min']:.1f} x"
    )
    print(
        f"exact vs DOP853 (rtol = atol = 1e-12): max relative difference in h1, h2 "
        f"{figures['exact_vs_dop853_max']:.2e}"
    )
    print(
        f"LSODA (odeint) vs exact: median relative error in h1, h2 "
        f"{figures['lsoda_vs_exact_median']:.2e}"
    )
    if "cvode_median_s" in figures:
        print(
            f"CVODE (BDF)       median {figures['cvode_median_s'] * 1e3:9.3f} ms per case "
            f"(rtol = atol = 1e-12): the exact solver is {figures['cvode_speedup_median']:.0f} x "
            f"faster (median); CVODE's relative error in h1, h2: median "
            f"{figures['cvode_vs_exact_median']:.1e}, largest {figures['cvode_vs_exact_max']:.1e}"
            f" (of the runs it finished; it failed on {figures['cvode_failed']} of {args.cases})"
        )
    eps, mu, tau_ratio = figures["worst_case"]
    print(
        f"where exact and DOP853 differ most (eps {eps:.4g}, mu {mu:.4g}, tau_ratio "
        f"{tau_ratio:.4g}), relative error against the 40-digit reference (twoball.studies.truth): "
        f"exact {figures['worst_exact_vs_truth']:.1e}, "
        f"DOP853 {figures['worst_dop853_vs_truth']:.1e}"
    )
    return 0


# sweep


def _add_sweep(subparsers: argparse._SubParsersAction) -> None:
    from twoball.stacks.model import HERTZ_LARGEST_MASS, HERTZ_SMALLEST_RESTITUTION

    hertz_limits = {
        "eps": f" (hertz: from {HERTZ_SMALLEST_RESTITUTION:g})",
        "mu": f" (hertz: up to {HERTZ_LARGEST_MASS:g})",
    }
    parser = subparsers.add_parser(
        "sweep",
        help="compute h1, h2, contacts and ratios over a grid into a resumable Zarr store",
        description="Sweep the exact solver over a grid of (eps, mu, tau_ratio). A run that is "
        "stopped (even by kill -9) resumes when started again with the same arguments.",
    )
    parser.add_argument("store", type=_store, help="output Zarr directory (e.g. cube.zarr)")
    for name in SWEEP_AXES:
        parser.add_argument(
            f"--{name.replace('_', '-')}",
            required=True,
            help="VALUE or START:STOP:COUNT[:linear|log], end points included, in "
            f"{allowed_range(name)}{hertz_limits.get(name, '')}; {Parameters.param[name].doc}",
        )
    _add_height(parser)
    parser.add_argument(
        "--eps12",
        type=_number,
        default=None,
        help=f"ball-ball restitution in {allowed_range('eps12')} (default: eps)",
    )
    parser.add_argument(
        "--chunks",
        default=None,
        help="chunk sizes E,M,T (default: whole mu-tau planes, ~12 500 drops a chunk)",
    )
    parser.add_argument(
        "--dtype", choices=("float64", "float32"), default="float64", help="stored floats"
    )
    parser.add_argument("--workers", type=_WORKERS, help="local threads (default: all cores)")
    parser.add_argument("--scheduler", default=None, help="Dask distributed scheduler address")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.add_argument(
        "--force",
        default="linear",
        type=_sweep_force,
        metavar="linear|hertz",
        help="the contact force: linear (default, the exact solver) or hertz (two balls, the "
        "compiled Hertz path; --height is then in Hertz units, docs/model.md)",
    )
    parser.add_argument(
        "--large",
        action="store_true",
        help=f"undertake more than {MAX_SWEEP_DROPS:,} drops (hertz: more than "
        f"{MAX_HERTZ_DROPS:,}), about an hour's work",
    )
    parser.set_defaults(func=_sweep)


def _sweep_force(text: str) -> str:
    """``sweep --force``: linear or hertz (argparse reports anything else)."""
    if text not in SWEEP_FORCES:
        raise argparse.ArgumentTypeError(f"must be linear or hertz; got {text!r}")
    return text


def _sweep(args: argparse.Namespace) -> int:
    from twoball.batch.sweep import Grid, max_drops, parse_axis, plan, sweep

    axes = [parse_axis(name, getattr(args, name)) for name in SWEEP_AXES]
    chunks = None
    if args.chunks is not None:
        try:
            chunks = tuple(int(part) for part in args.chunks.split(","))
        except ValueError:
            raise ParameterError(
                f"chunks must be three integers E,M,T; got {args.chunks!r}"
            ) from None
    grid = Grid(
        *axes,
        height=args.height,
        eps12=args.eps12,
        chunks=chunks,
        dtype=args.dtype,
        force=args.force,
    )
    undertaking = plan(grid, args.workers or os.cpu_count() or 1)
    if grid.size > max_drops(grid) and not args.large:
        raise ParameterError(
            f"refusing {undertaking}: more than {max_drops(grid):,} drops needs --large"
        )
    say_if_compiling(args)
    print(f"sweep {args.store}: {undertaking}", flush=True)  # on stdout: --quiet keeps it
    try:
        sweep(
            grid, args.store, scheduler=args.scheduler, workers=args.workers,
            progress=not args.quiet,
        )  # fmt: skip
    except OSError as error:
        # a file the sweep makes beside or inside the store (STORE.lock, a chunk): name the
        # store the user gave, and the file only in passing
        if error.filename is None or error.filename == args.store:
            raise
        raise OSError(
            error.errno, f"cannot write the store ({error.strerror}: {error.filename})", args.store
        ) from None
    print(f"{args.store}: {grid.size} cases, {len(grid.chunk_slices())} chunks, complete")
    return 0


# report


def _add_report(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "report", help="the paper's headline numbers beside ours (from the shipped cubes)"
    )
    parser.add_argument(
        "--paper-cube", type=_path, default="paper", help="cube name or .zarr path (paper)"
    )
    parser.add_argument(
        "--contacts-cube", type=_path, default="contacts", help="cube name or .zarr path (contacts)"
    )
    parser.add_argument(
        "--hertz-cubes",
        type=_path,
        default=None,
        help="Hertz cubes, comma-separated names or .zarr paths, or none (default: the shipped "
        "hertz-h1e2,hertz-h1e4)",
    )
    parser.set_defaults(func=_report)


def _report(args: argparse.Namespace) -> int:
    from twoball.studies.report import markdown, paper_table

    hertz = None  # the shipped Hertz cubes
    if args.hertz_cubes is not None:
        names = [part.strip() for part in args.hertz_cubes.split(",")]
        hertz = () if names == ["none"] else tuple(names)
    print(markdown(paper_table(args.paper_cube, args.contacts_cube, hertz)))
    return 0


# precision


def _add_precision(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "precision", help="error against run time of every method (work-precision diagram)"
    )
    parser.add_argument("--out", type=_path, required=True, help="directory for the CSV and PNG")
    parser.add_argument(
        "--repeats", type=_integer_in(1, 1000), default=3, help="timed repeats per run (median)"
    )
    parser.add_argument(
        "--budget",
        type=_seconds,
        default=20.0,
        help="seconds: a method slower than this at one tolerance skips the tighter ones",
    )
    parser.add_argument(
        "--no-truth", action="store_true", help="skip the 40-digit check of the exact solver"
    )
    parser.set_defaults(func=_precision)


def _precision(args: argparse.Namespace) -> int:
    from twoball.studies.precision import run_study

    run_study(args.out, repeats=args.repeats, budget=args.budget, truth=not args.no_truth)
    return 0


# stability


def _add_stability(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "stability", help="every method on stiff and extreme cases, and the H-convergence"
    )
    parser.add_argument("--out", type=_path, required=True, help="directory for the CSVs and PNGs")
    parser.add_argument(
        "--cap", type=_seconds, default=10.0, help="seconds per run before 'too slow'"
    )
    parser.add_argument("--workers", type=_WORKERS, default=2, help="worker processes (default 2)")
    parser.add_argument("--quick", action="store_true", help="base case sweeps only, no corners")
    parser.set_defaults(func=_stability)


def _stability(args: argparse.Namespace) -> int:
    from twoball.studies.stability import run_study

    run_study(args.out, cap=args.cap, workers=args.workers, quick=args.quick)
    return 0


# many-contacts


def _add_many_contacts(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "many-contacts", help="the exact solver against the 40-digit reference on many contacts"
    )
    parser.add_argument("--out", type=_path, required=True, help="directory for many_contacts.csv")
    parser.add_argument(
        "--count", type=_integer_in(1, 1000), default=20, help="drops in the sample (20)"
    )
    parser.add_argument(
        "--seed",
        type=_integer_in(0, 2**32 - 1),
        default=10,
        help="seed of the sample (10, the one docs/accuracy.md quotes)",
    )
    parser.add_argument("--workers", type=_WORKERS, default=2, help="worker processes (2)")
    parser.set_defaults(func=_many_contacts)


def _many_contacts(args: argparse.Namespace) -> int:
    from twoball.studies import truth  # noqa: F401  (mpmath, here: not in each worker)
    from twoball.studies.many_contacts import run_study

    run_study(args.out, count=args.count, seed=args.seed, workers=args.workers)
    return 0


# The commands, in the order --help lists them.
def _add_serve(subparsers: argparse._SubParsersAction) -> None:
    subparsers.add_parser(
        "serve",
        help="serve the classroom explorer at /app ('twoball serve --help' lists its options)",
        add_help=False,
    )


def _serve(options: list[str]) -> int:
    """``twoball serve``: Panel's serve command on the explorer (the app extra), which parses
    its own options (twoball_app/serve.py, in the repository's app/). Its help is there
    without the extra too, with what to install."""
    try:
        from twoball_app import serve
    except ModuleNotFoundError as error:
        if not {"-h", "--help"} & set(options) or EXTRAS.get(error.name or "") != "app":
            raise
        print(
            "usage: twoball serve [--port PORT] [--address ADDRESS] [--num-procs N] [panel serve "
            "options]\n\nServe the classroom explorer at /app. It needs the 'app' extra: pip "
            "install 'twoball[app]'; then 'twoball serve --help' lists every option."
        )
        return 0
    return serve.main(options)


COMMANDS = (
    _add_simulate,
    _add_stack,
    _add_bench,
    _add_sweep,
    _add_report,
    _add_precision,
    _add_stability,
    _add_many_contacts,
    _add_serve,
)


def _one_line(text: object) -> str:
    """The text with line breaks and other unprintable characters escaped, as repr would."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in str(text))


def build_parser() -> argparse.ArgumentParser:
    """The ``twoball`` parser with every command."""
    from twoball.version import __version__

    parser = _Parser(prog="twoball", description="The two-ball bounce, solved exactly.")
    parser.add_argument("--version", action="version", version=f"twoball {__version__}")
    subparsers = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for add in COMMANDS:
        add(subparsers)
    return parser


def kernels_used(args: argparse.Namespace) -> str | None:
    """The kernel module a command's runs spend their time in (None: it solves nothing)."""
    if args.command == "report":
        return None
    if getattr(args, "force", None) == "hertz":
        return "twoball.kernels.hertz"
    return "twoball.kernels.stack" if args.command == "stack" else "twoball.kernels.runs"


def say_if_compiling(args: argparse.Namespace) -> None:
    """One line on stderr when the command's kernels are not compiled yet on this machine: the
    first run then spends seconds to minutes in numba's compiler, silently otherwise. Said once
    the command's parameters are checked (a refused one is the only line, not after it)."""
    from twoball import jit

    module = kernels_used(args)
    if module is not None and not jit.compiled_on_disk(module):
        print(
            "twoball: compiling the solver for its first use on this machine (about 40 s for a "
            "drop, 2 minutes for a stack, more on a busy machine; kept for later runs)...",
            file=sys.stderr,
            flush=True,
        )


# the commands that say whether they compile once they have checked their parameters
CHECKED_FIRST = (_simulate, _stack, _sweep)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``twoball`` console script; returns the exit status."""
    argv = sys.argv[1:] if argv is None else argv
    try:
        if argv[:1] == ["serve"]:
            return _serve(argv[1:])
        args = build_parser().parse_args(argv)
        if args.func not in CHECKED_FIRST:
            say_if_compiling(args)
        status = args.func(args)
        sys.stdout.flush()  # a closed reader is found here, not at the interpreter's exit
        return status
    except BrokenPipeError:
        # the reader stopped early (twoball ... | head): end quietly, as a Unix tool does, and
        # send what is still buffered nowhere (Python's own recipe, docs: signal, SIGPIPE)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 128 + 13  # the status of a process ended by SIGPIPE
    except ParameterError as error:
        print(f"twoball: error: {_one_line(error)}", file=sys.stderr)
        return 2
    except OSError as error:
        if error.filename is None:  # not about a path: a real fault, keep its traceback
            raise
        where, what = _one_line(error.filename), _one_line(error.strerror or error)
        print(f"twoball: error: {where}: {what}", file=sys.stderr)
        return 2
    except SolverError as error:  # a known way for a run to fail: said in one line, status 1
        print(f"twoball: solver failed: {_one_line(error)}", file=sys.stderr)
        return 1
    except ModuleNotFoundError as error:
        extra = EXTRAS.get((error.name or "").partition(".")[0])
        if extra is None:
            raise
        print(
            f"twoball: error: this command needs the {extra!r} extra (no module named "
            f"{error.name!r}): pip install 'twoball[{extra}]'",
            file=sys.stderr,
        )
        return 2
