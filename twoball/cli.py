"""The ``twoball`` command line.

Bad input never shows a traceback: a :class:`~twoball.errors.ParameterError` (or argparse's own
complaint) prints one line on stderr and exits with status 2. A run that is no answer (a
:class:`~twoball.errors.SolverError`: stuck root finder, phase limit) prints one line and exits
with status 1. Any other exception is a bug and keeps its traceback.
Each subcommand lives in the module of its idea, which adds its own parser with
``add_parser(subparsers)`` and sets ``func`` to a function of the parsed arguments.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys

from twoball.errors import ParameterError, SolverError

# The modules that contribute subcommands, in the order --help lists them.
SUBCOMMAND_MODULES = (
    "twoball.cli",
    "twoball.studies.bench",
    "twoball.sweep",
    "twoball.studies.report",
    "twoball.studies.precision",
    "twoball.studies.stability",
)


# The optional dependencies, by the extra that installs them (pyproject.toml).
EXTRAS = {
    "xarray": "sweep",
    "zarr": "sweep",
    "dask": "sweep",
    "distributed": "sweep",
    "tqdm": "sweep",
    "matplotlib": "studies",
    "mpmath": "studies",
}


class UsageError(ParameterError):
    """Bad input on the command line: reported in one line, exit status 2."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # argparse's own errors: one line, status 2
        raise UsageError(message)


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """``twoball simulate``: one drop, its observables as text or JSON."""
    parser = subparsers.add_parser("simulate", help="simulate one drop and print its bounces")
    parser.add_argument("--eps", type=float, required=True, help="restitution eps in (0, 1]")
    parser.add_argument("--mu", type=float, required=True, help="mass ratio m2/m1 > 0")
    parser.add_argument("--tau-ratio", type=float, required=True, help="tau_d/tau_f >= 0")
    parser.add_argument(
        "--eps12", type=float, default=None, help="ball-ball restitution (default: eps)"
    )
    parser.add_argument("--height", type=float, default=1e4, help="dimensionless drop height H > 0")
    parser.add_argument(
        "--method", default="exact", help="exact, LSODA, Radau, BDF, DOP853, RK45 or odeint"
    )
    parser.add_argument(
        "--until", type=until_argument, default="second", help="first, second or a time"
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.set_defaults(func=_simulate)


def _simulate(args: argparse.Namespace) -> int:
    from twoball import simulate

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
    if args.json:
        print(json.dumps(summary))
        return 0
    width = max(len(key) for key in summary)
    for key, value in summary.items():
        shown = f"{value:.12g}" if isinstance(value, float) else value
        print(f"{key:<{width}}  {'-' if value is None else shown}")
    return 0


def until_argument(text: str) -> str | float:
    """``--until``: "first", "second" or a number (argparse reports anything else)."""
    try:
        return text if text in ("first", "second") else float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"first, second or a number; got {text!r}") from None


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="twoball", description="The two-ball bounce, solved exactly.")
    subparsers = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for name in SUBCOMMAND_MODULES:
        importlib.import_module(name).add_parser(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``twoball`` console script; returns the exit status."""
    try:
        args = build_parser().parse_args(argv)
        return args.func(args)
    except ParameterError as error:
        print(f"twoball: error: {error}", file=sys.stderr)
        return 2
    except OSError as error:
        if error.filename is None:  # not about a path: a real fault, keep its traceback
            raise
        print(f"twoball: error: {error.filename}: {error.strerror or error}", file=sys.stderr)
        return 2
    except SolverError as error:  # a known way for a run to fail: said in one line, status 1
        print(f"twoball: solver failed: {error}", file=sys.stderr)
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
