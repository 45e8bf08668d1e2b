"""Stiff and extreme cases: does each method finish, in what time, and is it right?

``twoball stability --out DIR`` runs the exact solver over a grid of extreme parameters (mu from
1e-6 to 1e2, eps from 0.02 through exp(-2), the damping branch switch, to 0.999999 and exactly
1, tau_d/tau_f from 0 to 10, H from 1 to 1e8) and the scipy methods over a subset of it, each run
in a worker process killed after a time cap. It writes ``DIR/stability.csv`` and
``DIR/stability.png``, and the convergence of the ratios as H grows (docs/model.md, "Initial
condition", on H) to
``DIR/h_convergence.csv`` and ``DIR/h_convergence.png``.

What went wrong is detected, not assumed (:func:`diagnose`), from the run's own sampled
trajectory and against the exact solver:

- missed contact: fewer contact intervals than the exact solver before the same time, or a sample
  where the clamped force (recomputed from the sampled state, docs/model.md, "Bodies, coordinates,
  forces") pushes outside every
  contact interval the method reported;
- passed through: an overlap X2 - X1 deeper than the energy allows (:func:`max_compression`);
- energy gained: the energy E of :func:`energy` rising along the trajectory (with the potential
  1/2 min(eta, 0)^2 of each contact, E is a Lyapunov function of the clamped model, so any rise
  beyond rounding is a numerical error);
- step-size failure: the solver's own message; too slow: the cap was hit.
"""

from __future__ import annotations

import csv
import math
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from twoball.batch.workers import Workers
from twoball.errors import ParameterError, Status
from twoball.kernels.codes import ROUNDING  # per phase, of the exact solver's state
from twoball.model import check_parameters
from twoball.observables import BALLS, FLOOR, relative_error
from twoball.reference import METHODS as REFERENCE_METHODS
from twoball.solve import simulate
from twoball.studies import precision

# The study's checks read the dense solution, which CVODE does not give here: scipy's methods.
METHODS = ("exact", *REFERENCE_METHODS)

if TYPE_CHECKING:
    from matplotlib.figure import Figure

EPS_BRANCH_SWITCH = math.exp(-2.0)
GRID = {
    "eps": (0.02, EPS_BRANCH_SWITCH, 0.5, 0.9, 0.999999, 1.0),
    "mu": (1e-6, 1e-4, 1e-2, 1.0, 1e2),
    "tau_ratio": (0.0, 1e-3, 0.3, 1.0, 10.0),
    "height": (1.0, 1e2, 1e4, 1e8),
}
BASE = {"eps": 0.816, "mu": 0.05, "tau_ratio": 0.3, "height": 1e4}
# Corners where several extremes meet (eps, mu, tau_ratio, height), and the paper's close-up.
CORNERS = (
    (1.0, 1e-6, 0.0, 1e4),
    (0.02, 1e2, 10.0, 1.0),
    (0.999999, 1e-4, 0.01, 1e8),
    (EPS_BRANCH_SWITCH, 1e-2, 1e-3, 1e4),
    (0.9, 1e-6, 1.0, 1e2),
    (0.9, 0.01, 0.01, 1e4),
)
SCIPY_TOLERANCE = 1e-8
# A tight run that counts the contacts independently of the exact solver.
CONTACT_CHECK = ("DOP853", 1e-11)
EXACT_LIMIT_SECONDS = 1.0
RIGHT_RELATIVE_ERROR = 1e-4  # a scipy result within this of the exact one counts as right
ENERGY_RISE_SCIPY = 1e-6  # well beyond a tolerance of 1e-8: a real gain, not truncation noise


@dataclass(frozen=True)
class StabilityRow:
    """One method's run on one case (:func:`diagnose`), completed by the comparison with the
    exact solver (:func:`judge`): read by the figure (:func:`stability_figure`) and the table
    (:func:`write_csv`, the fields of :data:`COLUMNS`). None where a figure was not measured (a
    run that crashed or was killed, a comparison not made)."""

    eps: float
    mu: float
    tau_ratio: float
    height: float
    method: str
    finished: bool
    seconds: float
    verdict: str | None = None  # right, wrong, failed or too slow (VERDICT_COLOURS), once judged
    problems: list[str] = field(default_factory=list)
    reason: str = ""
    h1: float | None = None
    h2: float | None = None
    rel_err_h1: float | None = None
    rel_err_h2: float | None = None
    ball_contacts: int | None = None
    exact_ball_contacts: int | None = None
    energy_rise: float | None = None
    deepest_overlap: float | None = None
    end_time: float | None = None  # not in the table: the comparison's
    contact_starts: list[float] = field(default_factory=list)

    @property
    def case(self) -> tuple[float, float, float, float]:
        """(eps, mu, tau_ratio, height)."""
        return (self.eps, self.mu, self.tau_ratio, self.height)


# the table's columns: every field but the two the comparison needs
COLUMNS = tuple(
    f.name for f in fields(StabilityRow) if f.name not in ("end_time", "contact_starts")
)


def grid_cases() -> list[tuple[float, float, float, float]]:
    """Every combination of the :data:`GRID` values: (eps, mu, tau_ratio, height)."""
    return [
        (eps, mu, tau_ratio, height)
        for eps in GRID["eps"]
        for mu in GRID["mu"]
        for tau_ratio in GRID["tau_ratio"]
        for height in GRID["height"]
    ]


def scipy_cases() -> list[tuple[float, float, float, float]]:
    """The subset run with every method: each axis of :data:`GRID` swept through :data:`BASE`,
    then the :data:`CORNERS`."""
    cases = []
    for axis, values in GRID.items():
        for value in values:
            case = {**BASE, axis: value}
            cases.append((case["eps"], case["mu"], case["tau_ratio"], case["height"]))
    return list(dict.fromkeys([*cases, *CORNERS]))


def energy(x1, x2, v1, v2, mu: float):
    """E = (v1^2 + mu v2^2)/2 + x1 + mu x2 + min(x1, 0)^2/2 + min(x2 - x1, 0)^2/2 (units of
    k (m1 g / k)^2); never increases along an exact solution of the clamped model (docs/model.md,
    "Bodies, coordinates, forces")."""
    x1, x2, v1, v2 = (np.asarray(a, dtype=float) for a in (x1, x2, v1, v2))
    floor = np.minimum(x1, 0.0)
    ball = np.minimum(x2 - x1, 0.0)
    return 0.5 * (v1 * v1 + mu * v2 * v2) + x1 + mu * x2 + 0.5 * (floor * floor + ball * ball)


def energy_rounding(x1, x2, v1, v2, mu: float, phases: int):
    """A bound on the rounding of :func:`energy` along an exact run of ``phases`` phases.

    The exact solver's state carries at most 16 units of rounding of its size S = |x1| + |x2| + |v1|
    + |v2| + 1 per phase (twoball/kernels/phases.py); through the gradient of E, bounded by 1 + mu +
    |v1| + mu |v2| + 2 (overlaps), that moves E by at most 16 eps S |grad E| per phase, and the
    phases add up.
    """
    x1, x2, v1, v2 = (np.asarray(a, dtype=float) for a in (x1, x2, v1, v2))
    overlaps = -np.minimum(x1, 0.0) - np.minimum(x2 - x1, 0.0)
    size = np.abs(x1) + np.abs(x2) + np.abs(v1) + np.abs(v2) + 1.0
    gradient = 1.0 + mu + np.abs(v1) + mu * np.abs(v2) + 2.0 * overlaps
    return ROUNDING * max(phases, 1) * size * gradient


def max_compression(mu: float, x1_0: float, x2_0: float) -> float:
    """The deepest ball overlap -eta12 that the energy at release allows.

    E >= -(1 + mu)^2/2 + mu eta + eta^2/2 for an overlap eta < 0 (the least E over x1, at
    x1 = -(1 + mu)), and E <= E(0) = x1_0 + mu x2_0, so -eta <= mu + sqrt(mu^2 + 2 E(0) +
    (1 + mu)^2).
    """
    return mu + math.sqrt(mu * mu + 2.0 * (x1_0 + mu * x2_0) + (1.0 + mu) ** 2)


def _energy_scale(mu: float, x1_0: float, x2_0: float) -> float:
    return abs(x1_0) + mu * abs(x2_0) + (1.0 + mu) ** 2


def _ball_contacts_before(result, end: float) -> int:
    return sum(1 for c in result.contacts if c.contact == BALLS and c.start < end)


def _unreported_pushes(result) -> list[str]:
    """Contacts whose recomputed clamped force pushes at a sample outside every reported
    interval of that contact."""
    trajectory = result.trajectory
    drop = result.drop
    x1, x2, v1, v2 = trajectory.x1, trajectory.x2, trajectory.v1, trajectory.v2
    slack = 1e-9 * (1.0 + np.abs(x1) + np.abs(x2) + np.abs(v1) + np.abs(v2))
    missed = []
    for contact, name, eta, rate, zeta in (
        (FLOOR, "floor", x1, v1, drop.zeta01),
        (BALLS, "ball", x2 - x1, v2 - v1, drop.zeta12),
    ):
        pushing = np.maximum(eta, eta + 2.0 * zeta * rate) < -slack
        covered = np.zeros_like(pushing)
        for c in result.contacts:
            if c.contact == contact:
                width = 1e-9 * (1.0 + abs(c.end))
                covered |= (trajectory.t >= c.start - width) & (trajectory.t <= c.end + width)
        if np.any(pushing & ~covered):
            missed.append(name)
    return missed


def _trajectory_problems(result, method: str) -> tuple[float, float, list[str]]:
    """Energy rise (relative), deepest overlap (over the allowed one) and the problems they and
    the sampled forces show."""
    drop = result.drop
    trajectory = result.trajectory
    problems = []
    x1, x2, v1, v2 = trajectory.x1, trajectory.x2, trajectory.v1, trajectory.v2
    e = energy(x1, x2, v1, v2, drop.mu)
    scale = _energy_scale(drop.mu, drop.x1_0, drop.x2_0)
    gain = e - np.minimum.accumulate(e)
    rise = float(np.max(gain)) / scale if e.size else 0.0
    if not np.all(np.isfinite(e)):
        rise = math.inf
    if method == "exact":
        # beyond the rounding the solver's own tolerance allows, accumulated over its phases
        phases = 2 * len(result.contacts) + len(result.apex_t) + 1
        rounding = energy_rounding(x1, x2, v1, v2, drop.mu, phases)
        gained = not np.all(gain <= rounding + np.maximum.accumulate(rounding))
    else:
        gained = rise > ENERGY_RISE_SCIPY
    if gained:
        problems.append("energy gained")
    overlap = trajectory.x2 - trajectory.x1
    deepest = float(-np.min(overlap)) / max_compression(drop.mu, drop.x1_0, drop.x2_0)
    if not math.isfinite(deepest) or deepest > 1.0:
        problems.append("passed through")
    problems += [f"missed {name} contact" for name in _unreported_pushes(result)]
    return rise, deepest, problems


def diagnose(
    eps: float, mu: float, tau_ratio: float, height: float, method: str, tolerance: float
) -> StabilityRow:
    """Run one method on one case with its trajectory sampled, and check it against the model.

    Returns the run's figures and the problems found without the exact solver (the comparison
    with it is :func:`judge`); never raises for a failing method.
    """
    check_parameters(eps, mu, tau_ratio, height=height)
    options = {} if method == "exact" else {"rtol": tolerance, "atol": tolerance}
    case = {"eps": eps, "mu": mu, "tau_ratio": tau_ratio, "height": height, "method": method}
    start = time.perf_counter()
    try:
        result = simulate(
            eps, mu, tau_ratio, height=height, method=method, dense_output=True, throw=False,
            **options,
        )  # fmt: skip
    except (ValueError, ArithmeticError, RuntimeError, MemoryError) as error:
        return StabilityRow(
            **case,
            finished=False,
            seconds=time.perf_counter() - start,
            reason=f"{type(error).__name__}: {error}",
            problems=["crashed"],
        )
    seconds = time.perf_counter() - start
    problems = []
    reason = result.reason or ""
    failed = result.status == Status.FAILED
    if failed:
        problems.append("step-size failure")
    rise = deepest = None
    # a failed scipy run's trajectory is undefined past the failure: nothing to check there
    if result.trajectory is not None and not failed:
        rise, deepest, found = _trajectory_problems(result, method)
        problems += found
    values = [v for v in (result.h1, result.h2) if v is not None]
    if not all(math.isfinite(v) for v in values):
        problems.append("non-finite result")
    return StabilityRow(
        **case,
        finished=not failed,
        seconds=seconds,
        reason=reason,
        problems=problems,
        h1=result.h1,
        h2=result.h2,
        end_time=result.end_time,
        contact_starts=[c.start for c in result.contacts if c.contact == BALLS],
        energy_rise=rise,
        deepest_overlap=deepest,
    )


def judge(row: StabilityRow, exact_row: StabilityRow | None) -> StabilityRow:
    """Complete a :func:`diagnose` row with the comparison against the exact solver's row (None:
    the case has none)."""
    problems = list(row.problems)
    found = {}
    if row.method == "exact":
        if row.finished and row.seconds > EXACT_LIMIT_SECONDS:
            problems.append("too slow")
    elif row.finished and exact_row is not None and exact_row.finished:
        end = min(row.end_time, exact_row.end_time)
        mine = sum(1 for s in row.contact_starts if s < end)
        theirs = sum(1 for s in exact_row.contact_starts if s < end)
        found.update(ball_contacts=mine, exact_ball_contacts=theirs)
        if mine < theirs:
            problems.append("missed ball contact")
        elif mine > theirs:
            problems.append("extra ball contact")
        for name in ("h1", "h2"):
            error = relative_error(getattr(row, name), getattr(exact_row, name))
            found[f"rel_err_{name}"] = error
            if error > RIGHT_RELATIVE_ERROR:
                problems.append(f"wrong {name}")
    if row.method == "exact" and row.finished:
        found.update(ball_contacts=len(row.contact_starts))
        found.update(exact_ball_contacts=len(row.contact_starts))
    problems = list(dict.fromkeys(problems))
    if not row.finished:
        verdict = "too slow" if problems == ["too slow"] else "failed"
    else:
        verdict = "right" if not problems else "wrong"
    return replace(row, **found, problems=problems, verdict=verdict)


def study(
    exact_cases: Iterable[tuple],
    scipy_subset: Iterable[tuple],
    *,
    methods: Sequence[str] = METHODS,
    cap: float = 10.0,
    workers: int = 2,
    check: tuple[str, float] | None = None,
    progress=None,
    diagnose_one: Callable[..., StabilityRow] | None = None,
) -> list[StabilityRow]:
    """The stability study: the exact solver on ``exact_cases``, every other method on
    ``scipy_subset`` (which must be among ``exact_cases``), each under a time cap.

    ``check``, a (method, tolerance) such as :data:`CONTACT_CHECK`, adds a tight run of that
    method on the subset, named "method tolerance", as an independent count of the contacts.
    ``diagnose_one`` replaces :func:`diagnose` in the workers (a module-level function).
    """
    exact_cases = [tuple(float(v) for v in case) for case in exact_cases]
    scipy_subset = [tuple(float(v) for v in case) for case in scipy_subset]
    tasks = [(*case, "exact", 0.0) for case in exact_cases]
    tasks += [
        (*case, method, SCIPY_TOLERANCE)
        for case in scipy_subset
        for method in methods
        if method != "exact"
    ]
    checked = len(tasks)
    if check is not None:
        tasks += [(*case, *check) for case in scipy_subset]
    rows: list[StabilityRow | None] = [None] * len(tasks)
    with Workers(workers, diagnose if diagnose_one is None else diagnose_one, cap=cap) as pool:
        for index, row, seconds in pool.results(tasks):
            if row is None:  # killed over the cap
                eps, mu, tau_ratio, height, method, _ = tasks[index]
                row = StabilityRow(
                    eps,
                    mu,
                    tau_ratio,
                    height,
                    method,
                    finished=False,
                    seconds=seconds,
                    reason=f"killed after {cap:g} s",
                    problems=["too slow"],
                )
            rows[index] = row
            if progress is not None:
                progress(row)
    if check is not None:
        name = f"{check[0]} {check[1]:g}"
        rows[checked:] = [replace(row, method=name) for row in rows[checked:]]
    exact_rows = {row.case: row for row in rows[: len(exact_cases)]}
    return [judge(row, exact_rows.get(row.case)) for row in rows]


def write_csv(rows: Sequence[StabilityRow], path: str | Path) -> None:
    """The judged rows as CSV with the columns :data:`COLUMNS`, problems joined by "; "."""
    shown = [{**asdict(row), "problems": "; ".join(row.problems)} for row in rows]
    precision.write_csv(shown, path, COLUMNS)


VERDICT_COLOURS = {
    "right": "#4caf50",
    "wrong": "#e53935",
    "failed": "#8e24aa",
    "too slow": "#fb8c00",
}


def stability_figure(rows: Sequence[StabilityRow]) -> Figure:
    """Left: verdict of every method on the scipy subset; right: the exact solver's run time
    over the whole grid, against the 1 s limit."""
    scipy_rows = [r for r in rows if r.method != "exact"]
    subset = list(dict.fromkeys(r.case for r in scipy_rows))
    methods = list(dict.fromkeys(r.method for r in rows))
    by_key = {(r.case, r.method): r for r in rows}
    from matplotlib.figure import Figure

    figure = Figure(figsize=(15, 0.32 * len(subset) + 2.5), layout="constrained")
    left, right = figure.subplots(1, 2, width_ratios=(2.2, 1))
    for i, case in enumerate(subset):
        for j, method in enumerate(methods):
            row = by_key.get((case, method))
            if row is None:
                continue
            left.add_patch(_rectangle(j, i, VERDICT_COLOURS[row.verdict]))
            text = _short(row)
            left.text(j + 0.5, i + 0.5, text, ha="center", va="center", fontsize=6.5)
    left.set_xlim(0, len(methods))
    left.set_ylim(len(subset), 0)
    left.set_xticks(np.arange(len(methods)) + 0.5, methods)
    left.xaxis.tick_top()
    left.set_yticks(
        np.arange(len(subset)) + 0.5,
        [f"eps={e:.6g} mu={m:g} tau={t:g} H={h:g}" for e, m, t, h in subset],
        fontsize=7,
    )
    handles = [_rectangle(0, 0, colour) for colour in VERDICT_COLOURS.values()]
    left.legend(
        handles,
        list(VERDICT_COLOURS),
        loc="upper left",
        bbox_to_anchor=(0, -0.01),
        ncols=4,
        fontsize=8,
    )
    left.set_title(
        f"Each method on stiff and extreme cases (scipy rtol = atol = {SCIPY_TOLERANCE:g}, last"
        " column: the tighter contact check);"
        " cell text: seconds and what went wrong",
        fontsize=9,
    )
    exact_rows = [r for r in rows if r.method == "exact"]
    seconds = np.array([r.seconds for r in exact_rows])
    colours = [VERDICT_COLOURS[r.verdict] for r in exact_rows]
    right.scatter(np.arange(len(exact_rows)), np.maximum(seconds, 1e-6), c=colours, s=8)
    right.axhline(EXACT_LIMIT_SECONDS, color="k", linestyle="--", linewidth=0.8)
    right.set_yscale("log")
    right.set_xlabel("grid case (eps, mu, tau_d/tau_f, H; in CSV order)")
    right.set_ylabel("run time to the second apex [s] (with trajectory sampling)")
    bad = sum(1 for r in exact_rows if r.verdict != "right")
    right.set_title(
        f"Exact solver, {len(exact_rows)} cases: {bad} not right (dashed: 1 s)",
        fontsize=9,
    )
    return figure


def _rectangle(x: float, y: float, colour: str):
    from matplotlib.patches import Rectangle

    return Rectangle((x, y), 1, 1, facecolor=colour, edgecolor="white", alpha=0.8)


ABBREVIATIONS = {
    "missed ball contact": "miss",
    "missed floor contact": "miss floor",
    "extra ball contact": "extra",
    "passed through": "through",
    "energy gained": "energy+",
    "step-size failure": "step fail",
    "too slow": "slow",
    "non-finite result": "nonfinite",
    "crashed": "crash",
}


def _short(row: StabilityRow) -> str:
    seconds = f"{row.seconds:.2g}s"
    problems = [ABBREVIATIONS.get(p, p) for p in row.problems]
    return seconds if not problems else seconds + "\n" + ",".join(problems[:3])


# H-convergence (docs/model.md, "Initial condition", on H): the paper says the ratios depend on
# (eps, mu,
# tau_d/tau_f) only; they do as H grows.
H_VALUES = tuple(10.0**k for k in range(1, 9))
H_POINTS = ((0.816, 0.05, 0.3), (0.9, 0.01, 0.01), (0.7, 0.1, 0.7), (0.816, 0.01, 0.05))


@dataclass(frozen=True)
class ConvergenceRow:
    """The four ratios and the ball contacts before the first apex of one drop at one height
    (:func:`h_convergence`), read by its figure and table (the fields: :data:`H_COLUMNS`)."""

    eps: float
    mu: float
    tau_ratio: float
    height: float
    h1_over_icm: float | None
    h2_over_h1: float | None
    h1_over_drop: float | None
    h2_over_drop: float | None
    contacts_first: int  # the ball contacts (a result's contacts_first[BALLS])


H_COLUMNS = tuple(f.name for f in fields(ConvergenceRow))


def h_convergence(
    points: Sequence[tuple[float, float, float]] = H_POINTS, heights: Sequence[float] = H_VALUES
) -> list[ConvergenceRow]:
    """The four ratios and the contact count at each point and height (exact solver)."""
    rows = []
    for eps, mu, tau_ratio in points:
        for height in heights:
            result = simulate(eps, mu, tau_ratio, height=height)
            rows.append(
                ConvergenceRow(
                    eps,
                    mu,
                    tau_ratio,
                    height,
                    h1_over_icm=result.h1_over_icm,
                    h2_over_h1=result.h2_over_h1,
                    h1_over_drop=result.h1_over_drop,
                    h2_over_drop=result.h2_over_drop,
                    contacts_first=result.contacts_first[BALLS],
                )
            )
    return rows


def h_convergence_figure(rows: Sequence[ConvergenceRow]) -> Figure:
    """h1/h_ICM and h2/h1 against H, one line per parameter point."""
    from matplotlib.figure import Figure

    figure = Figure(figsize=(10, 4), layout="constrained")
    axes = figure.subplots(1, 2)
    points = list(dict.fromkeys((r.eps, r.mu, r.tau_ratio) for r in rows))
    for index, point in enumerate(points):
        mine = [r for r in rows if (r.eps, r.mu, r.tau_ratio) == point]
        label = f"eps={point[0]:g}, mu={point[1]:g}, tau_d/tau_f={point[2]:g}"
        for axis, key in zip(axes, ("h1_over_icm", "h2_over_h1"), strict=True):
            values = [math.nan if getattr(r, key) is None else getattr(r, key) for r in mine]
            axis.plot([r.height for r in mine], values, marker="o", color=f"C{index}", label=label)
    for axis, name in zip(axes, ("h1 / h_ICM", "h2 / h1"), strict=True):
        axis.set_xscale("log")
        axis.set_xlabel("dimensionless drop height H = h k / (m1 g)")
        axis.set_ylabel(name)
        axis.grid(True, alpha=0.3)
    axes[0].legend(fontsize=7)
    figure.suptitle(
        "The ratios depend on H; they settle only as H grows (exact solver)", fontsize=10
    )
    return figure


def run_study(out: Path, *, cap: float = 10.0, workers: int = 2, quick: bool = False) -> None:
    """The stability study (``twoball stability``): every method on the stiff and extreme cases
    and the H-convergence; writes stability.csv/.png and h_convergence.csv/.png into out.
    ``quick`` runs the base case sweeps only, without the corners."""
    if not (math.isfinite(cap) and cap > 0):
        raise ParameterError(f"cap must be a number of seconds > 0; got {cap!r}")
    if workers < 1:
        raise ParameterError(f"workers must be at least 1; got {workers!r}")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    subset = scipy_cases()
    cases = grid_cases()
    if quick:
        subset = subset[: -len(CORNERS)]
        cases = subset
    else:
        cases = list(dict.fromkeys([*cases, *subset]))
    done = [0]
    total = len(cases) + len(subset) * len(METHODS)

    def progress(row: StabilityRow) -> None:
        done[0] += 1
        if done[0] % 50 == 0 or done[0] == total:
            print(f"  {done[0]}/{total} runs", flush=True)

    started = time.perf_counter()
    rows = study(cases, subset, cap=cap, workers=workers, check=CONTACT_CHECK, progress=progress)
    write_csv(rows, out / "stability.csv")
    stability_figure(rows).savefig(out / "stability.png", dpi=110)
    convergence = h_convergence()
    with open(out / "h_convergence.csv", "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=H_COLUMNS)
        writer.writeheader()
        writer.writerows(asdict(row) for row in convergence)
    h_convergence_figure(convergence).savefig(out / "h_convergence.png", dpi=110)
    print(
        f"{len(rows)} runs in {time.perf_counter() - started:.0f} s; wrote {out}/stability.csv,"
        " stability.png, h_convergence.csv, h_convergence.png"
    )
    for method in dict.fromkeys(r.method for r in rows):
        mine = [r for r in rows if r.method == method]
        counts = {v: sum(1 for r in mine if r.verdict == v) for v in VERDICT_COLOURS}
        print(f"  {method:12s} " + ", ".join(f"{k} {n}" for k, n in counts.items()))
