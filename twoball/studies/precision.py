"""Error against run time: every integrator over a range of tolerances.

:func:`work_precision` runs the exact solver and the scipy integrators of
:mod:`twoball.reference` on one drop, to the second apex (docs/model.md, "What is measured"), and
returns one row per method and tolerance: the relative errors in h1 and h2 against the exact
solver and the median run time. The exact solver's own error is established independently by
:mod:`twoball.studies.truth` (``twoball precision`` reports it beside the table).

``twoball precision --out DIR`` does this on the documented :data:`CASES` over the full range of
tolerances and writes ``DIR/work_precision.csv`` and ``DIR/work_precision.png``.
"""

from __future__ import annotations

import csv
import importlib.util
import math
import textwrap
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, is_dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from twoball import reference
from twoball.errors import ParameterError, Status
from twoball.model import DEFAULT_HEIGHT, check_parameters
from twoball.observables import BALLS, relative_error
from twoball.solve import simulate
from twoball.studies.conditioning import Comparison
from twoball.studies.timing import median_seconds

if TYPE_CHECKING:
    from matplotlib.figure import Figure

# CVODE (the cvode extra) joins the study where it is installed (not in the app's image)
CVODE_INSTALLED = importlib.util.find_spec("sksundae") is not None
METHODS = ("exact", *reference.IVP_METHODS, *(("CVODE",) if CVODE_INSTALLED else ()))
# Cheap enough for the app (a few seconds on benign cases); the command line uses FULL_TOLERANCES.
APP_TOLERANCES = (1e-3, 1e-6, 1e-9)
FULL_TOLERANCES = tuple(10.0**-k for k in range(3, 13))
# Once one run of a method takes longer than this, its tighter tolerances are not run (their
# rows say so with seconds = inf and NaN errors): tighter only gets slower.
APP_BUDGET_SECONDS = 2.0
REST_MARGIN = 1.5  # see measure_case
COLUMNS = ("method", "tolerance", "case", "rel_err_h1", "rel_err_h2", "seconds")
# Errors below this are drawn on it (a relative error of 0 has no place on a log axis).
ERROR_FLOOR = 1e-17
FAILED_ERROR = 10.0  # where failed runs (infinite error) are drawn


@dataclass(frozen=True)
class PrecisionRow:
    """One run of the work-precision study (:func:`work_precision`): a method at a tolerance
    (None for the exact solver) on a case, its relative errors in h1 and h2 against the exact
    solver (inf: it failed or missed a bounce; NaN: nobody has that bounce) and its run time.
    The figures and the app read these; :data:`COLUMNS` are its fields."""

    method: str
    tolerance: float | None
    case: str
    rel_err_h1: float
    rel_err_h2: float
    seconds: float

    @property
    def error(self) -> float:
        """The larger relative error of h1 and h2, NaN (no such bounce for anyone) counting as
        no error."""
        return max(_finite_or(self.rel_err_h1), _finite_or(self.rel_err_h2))

    @property
    def failed(self) -> bool:
        """The failure rule: the method failed or missed a bounce (an infinite error)."""
        return not math.isfinite(self.error)

    @property
    def shown_error(self) -> float:
        """The error as drawn: floored at :data:`ERROR_FLOOR`, a failure at
        :data:`FAILED_ERROR`."""
        return FAILED_ERROR if self.failed else max(self.error, ERROR_FLOOR)


# The documented cases of ``twoball precision``: name -> (eps, mu, tau_ratio), H = 1e4.
CASES = {
    "paper close-up": (0.9, 0.01, 0.01),
    "benign": (0.816, 0.05, 0.3),
    "stiff, small mu": (0.816, 1e-4, 0.1),
    "overdamped": (0.12, 0.02, 1.0),
    "nearly elastic": (0.999, 0.05, 0.3),
}


def case_label(eps: float, mu: float, tau_ratio: float, eps12: float | None, height: float) -> str:
    """A short name of one drop for tables and legends."""
    label = f"eps={eps:g}, mu={mu:g}, tau_ratio={tau_ratio:g}, H={height:g}"
    return label if eps12 is None else f"{label}, eps12={eps12:g}"


def work_precision(
    eps: float,
    mu: float,
    tau_ratio: float,
    *,
    eps12: float | None = None,
    height: float = DEFAULT_HEIGHT,
    methods: Sequence[str] | None = None,
    tolerances: Sequence[float] | None = None,
    repeats: int = 1,
) -> list[PrecisionRow]:
    """Error against run time of each method at each tolerance, on one drop.

    methods: any of :data:`METHODS` (default all); tolerances: rtol = atol for the scipy methods
    (default :data:`APP_TOLERANCES`). Returns rows with keys ``method, tolerance, case,
    rel_err_h1, rel_err_h2, seconds``: tolerance None for the exact solver; errors relative to
    the exact solver (0 for itself), inf where a method failed or missed a bounce the exact
    solver found, NaN where the exact solver has no such bounce; seconds the median of
    ``repeats`` runs. A failing method never raises. Raises ValueError for bad parameters.
    """
    return measure_case(
        case_label(eps, mu, tau_ratio, eps12, height),
        eps,
        mu,
        tau_ratio,
        eps12=eps12,
        height=height,
        methods=methods,
        tolerances=tolerances,
        repeats=repeats,
        budget=APP_BUDGET_SECONDS,
    )


def measure_case(
    case: str,
    eps: float,
    mu: float,
    tau_ratio: float,
    *,
    eps12: float | None = None,
    height: float = DEFAULT_HEIGHT,
    methods: Sequence[str] | None = None,
    tolerances: Sequence[float] | None = None,
    repeats: int = 1,
    budget: float = math.inf,
) -> list[PrecisionRow]:
    """:func:`work_precision` with a case name and a per-method time budget (see
    :data:`APP_BUDGET_SECONDS`)."""
    check_parameters(eps, mu, tau_ratio, eps12=eps12, height=height)
    methods = METHODS if methods is None else tuple(methods)
    unknown = [m for m in methods if m not in METHODS]
    if unknown:
        raise ParameterError(f"methods must be among {', '.join(METHODS)}; got {unknown!r}")
    tolerances = APP_TOLERANCES if tolerances is None else tuple(float(t) for t in tolerances)
    for tol in tolerances:
        if not (math.isfinite(tol) and 0.0 < tol < 1.0):
            raise ParameterError(f"tolerances must be finite numbers in (0, 1); got {tol!r}")
    if repeats < 1:
        raise ParameterError(f"repeats must be at least 1; got {repeats!r}")
    drop = {"eps12": eps12, "height": height}
    truth = simulate(eps, mu, tau_ratio, **drop)  # also loads the compiled kernel
    # scipy cannot tell that the upper ball came to rest and would integrate to its time limit:
    # where the exact solver stopped at rest, run it to a little past that time instead
    until = "second" if truth.status == Status.DONE else REST_MARGIN * truth.end_time
    rows = []
    for method in methods:
        over_budget = False
        for tol in (None,) if method == "exact" else tolerances:
            row = {"method": method, "tolerance": tol, "case": case}
            if over_budget:
                rows.append(PrecisionRow(**row, rel_err_h1=math.nan, rel_err_h2=math.nan,
                                         seconds=math.inf))  # fmt: skip
                continue

            def run(method=method, tol=tol):
                if method == "exact":
                    return simulate(eps, mu, tau_ratio, **drop)
                return simulate(
                    eps, mu, tau_ratio, method=method, rtol=tol, atol=tol, until=until,
                    throw=False, **drop,
                )  # fmt: skip

            start = time.perf_counter()
            try:
                result = run()
            except (ValueError, ArithmeticError, RuntimeError):
                h1 = h2 = None
                seconds = time.perf_counter() - start
            else:
                h1, h2 = result.h1, result.h2
                first = time.perf_counter() - start
                seconds = first if repeats == 1 else median_seconds(run, repeats)
            over_budget = seconds > budget
            rows.append(
                PrecisionRow(
                    **row,
                    rel_err_h1=relative_error(h1, truth.h1),
                    rel_err_h2=relative_error(h2, truth.h2),
                    seconds=seconds,
                )
            )
    return rows


def write_csv(
    rows: Sequence[PrecisionRow | dict], path: str | Path, columns: Sequence[str] = COLUMNS
) -> None:
    """The rows (typed, or dicts) as CSV with the given columns (default :data:`COLUMNS`); None
    is written empty (the exact solver's tolerance), other keys are left out."""
    with open(path, "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=columns, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(asdict(row) if is_dataclass(row) else row for row in rows)


def work_precision_figure(rows: Sequence[PrecisionRow], title: str | None = None) -> Figure:
    """Error against run time, log-log, one panel per case and one line per method.

    The error of a run is the larger of its relative errors in h1 and h2; runs that failed or
    missed a bounce are drawn as crosses at the top of the panel.
    """
    cases = list(dict.fromkeys(row.case for row in rows))
    methods = list(dict.fromkeys(row.method for row in rows))
    columns = min(len(cases), 3)
    lines = math.ceil(len(cases) / columns)
    width = max(5.2 * columns, 7.0)
    from matplotlib.figure import Figure

    figure = Figure(figsize=(width, 4.2 * lines + 0.8), layout="constrained")
    axes = figure.subplots(lines, columns, squeeze=False).ravel()
    markers = dict(zip(METHODS, "*osD^vP", strict=False))
    for axis, case in zip(axes, cases, strict=False):
        for index, method in enumerate(methods):
            mine = [r for r in rows if r.case == case and r.method == method]
            color = f"C{index}"
            good = [(r.seconds, r.error, r) for r in mine if math.isfinite(r.seconds)]
            shown = [(s, r.shown_error) for s, _, r in good if not r.failed]
            failed = [s for s, _, r in good if r.failed]
            if shown:
                axis.plot(
                    [s for s, _ in shown],
                    [e for _, e in shown],
                    marker=markers.get(method, "o"),
                    color=color,
                    markersize=9 if method == "exact" else 5,
                    label=method,
                )
                for seconds, _, row in (good[0], good[-1]) if len(good) > 1 else ():
                    if row.tolerance is not None and not row.failed:
                        axis.annotate(
                            f"{row.tolerance:.0e}",
                            (seconds, row.shown_error),
                            fontsize=7,
                            color=color,
                            xytext=(4, 2),
                            textcoords="offset points",
                        )
            if failed:
                axis.plot(
                    failed,
                    [FAILED_ERROR] * len(failed),
                    linestyle="none",
                    marker="x",
                    color=color,
                    label=None if shown else method,
                )
        axis.set_xscale("log")
        axis.set_yscale("log")
        axis.axhline(FAILED_ERROR, color="0.7", linewidth=0.8, linestyle=":")
        axis.set_title(case, fontsize=10)
        axis.set_xlabel("run time per drop [s] (median)")
        axis.set_ylabel("relative error of h1, h2 (larger)")
        axis.grid(True, which="major", alpha=0.3)
    for axis in axes[len(cases) :]:
        axis.set_visible(False)
    handles, labels = axes[0].get_legend_handles_labels()
    if len(axes) > len(cases):  # a spare panel: the legend goes there, clear of the data
        figure.legend(handles, labels, loc="center", bbox_to_anchor=_panel_centre(axes[-1]))
    else:
        axes[0].legend(fontsize=8, loc="upper right")
    figure.suptitle(
        "\n".join(
            textwrap.fill(line, int(width * 13))
            for line in (
                title or _title(any(r.method == "exact" and r.rel_err_h1 > 0 for r in rows))
            ).split("\n")
        ),
        fontsize=10,
    )
    return figure


def _panel_centre(axis) -> tuple[float, float]:
    """The centre of a panel in figure coordinates."""
    box = axis.get_position()
    return (box.x0 + box.width / 2, box.y0 + box.height / 2)


def _finite_or(value: float) -> float:
    """NaN (no such bounce for anyone) counts as no error; inf stays inf."""
    return 0.0 if math.isnan(value) else value


def plot_work_precision(
    rows: Sequence[PrecisionRow], path: str | Path, title: str | None = None
) -> None:
    """Write :func:`work_precision_figure` of the rows to ``path`` (PNG)."""
    work_precision_figure(rows, title).savefig(path, dpi=110)


# The exact solver's own error on these cases is measured against :mod:`twoball.studies.truth`.
TRUTH_COLUMNS = (
    "case",
    "h1_truth",
    "h2_truth",
    "rel_err_h1",
    "rel_err_h2",
    "contacts_first",
    "contacts_first_truth",
    "truth_seconds",
    "cond_h1",
    "cond_h2",
)


def _title(with_truth: bool, height: float | None = None) -> str:
    """Figure title: what the axes, labels and markers mean."""
    exact = (
        "the exact solver's star: its error against a 40-digit reference"
        if with_truth
        else f"the exact solver is the reference (its star drawn at {ERROR_FLOOR:.0e})"
    )
    at = "" if height is None else f", H = {height:g}"
    return (
        f"Error against run time to the second apex{at}; labels: rtol = atol of the loosest and"
        f" tightest run\ncrosses at 10: the run failed or missed a bounce; {exact}"
    )


@dataclass(frozen=True)
class TruthRow(Comparison):
    """One documented case's exact run against the 40-digit reference
    (:func:`exact_against_truth`): the comparison, the case's name, the reference heights as
    text and the reference's run time; :data:`TRUTH_COLUMNS` are its fields."""

    case: str
    h1_truth: str
    h2_truth: str
    truth_seconds: float


def exact_against_truth(cases: dict[str, tuple[float, float, float]]) -> list[TruthRow]:
    """The exact solver's relative errors in h1 and h2 against the 40-digit reference, with
    each case's conditioning (:mod:`twoball.studies.conditioning`)."""
    from twoball.studies.conditioning import against_reference, reference_text
    from twoball.studies.truth import solve_truth

    rows = []
    for case, parameters in cases.items():
        start = time.perf_counter()
        truth = solve_truth(*parameters)
        seconds = time.perf_counter() - start
        compared = against_reference(*parameters, truth.h1, truth.h2, truth.contacts_first[BALLS])
        rows.append(
            TruthRow(
                **asdict(compared),
                case=case,
                h1_truth=reference_text(truth.h1),
                h2_truth=reference_text(truth.h2),
                truth_seconds=seconds,
            )
        )
    return rows


def run_study(out: Path, *, repeats: int = 3, budget: float = 20.0, truth: bool = True) -> None:
    """The work-precision study (``twoball precision``): measure every method on the documented
    cases, write work_precision.csv and .png (and exact_vs_truth.csv with ``truth``) into out."""
    if repeats < 1:
        raise ParameterError(f"repeats must be at least 1; got {repeats!r}")
    if not budget > 0:
        raise ParameterError(f"budget must be a number of seconds > 0; got {budget!r}")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    truth_rows = exact_against_truth(CASES) if truth else []
    established = {row.case: row for row in truth_rows}
    rows = []
    for case, (eps, mu, tau_ratio) in CASES.items():
        print(f"{case}: eps={eps:g}, mu={mu:g}, tau_ratio={tau_ratio:g}, H=1e4", flush=True)
        case_rows = measure_case(
            case,
            eps,
            mu,
            tau_ratio,
            tolerances=FULL_TOLERANCES,
            repeats=repeats,
            budget=budget,
        )
        for index, row in enumerate(case_rows):  # the exact solver's own error, where known
            if row.method == "exact" and case in established:
                truth_row = established[case]
                case_rows[index] = replace(
                    row, rel_err_h1=truth_row.rel_err_h1, rel_err_h2=truth_row.rel_err_h2
                )
        rows += case_rows
    write_csv(rows, out / "work_precision.csv")
    plot_work_precision(rows, out / "work_precision.png", _title(bool(truth_rows), DEFAULT_HEIGHT))
    written = ["work_precision.csv", "work_precision.png"]
    if truth_rows:
        write_csv(truth_rows, out / "exact_vs_truth.csv", TRUTH_COLUMNS)
        written.append("exact_vs_truth.csv")
        from twoball.studies.conditioning import within_rule

        worst = max(max(r.rel_err_h1, r.rel_err_h2) for r in truth_rows)
        ratio = max(max(r.rel_err_h1 / r.cond_h1, r.rel_err_h2 / r.cond_h2) for r in truth_rows)
        outside = sum(not within_rule(r) for r in truth_rows)
        print(
            f"exact solver against the 40-digit reference: largest relative error {worst:.1e},"
            f" {ratio:.1f} times the conditioning at worst; outside the rule on {outside}"
        )
    print(f"wrote {', '.join(str(out / name) for name in written)}")
