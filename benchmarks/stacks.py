"""Benchmark and comparison: stacks of N balls (twoball.stacks.stack, twoball.stacks.hertz).

    .venv/bin/python benchmarks/stacks.py [--repeats 7] [--write]

Prints the median CPU time of one drop to the top ball's second apex for N = 2 to 8 balls (the
linear force, exact; the targets: 0.5 ms for N = 3, 30 ms for N = 8) and for the Hertz force
(compiled: targets 1 ms for two balls, 3 ms for three, 50 ms for six, and within 20 times the
linear stack; the DOP853 reference method for N <= 3), with ``twoball.simulate`` (N = 2) as the
baseline in the same process. Then compares the two force
laws on two-ball drops and on stacks (h1 against the ICM chain, h2/h1, contacts before h1), with
how far h1 and h2 move when H moves by one ulp (their conditioning). ``--write`` puts the
timings into docs/performance.md and the comparison into docs/stacks.md.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from pathlib import Path

from perfdoc import write_section  # benchmarks/ is on the path of a script run from it

import twoball
from twoball.stacks import simulate_stack

STACKS_DOC = Path(__file__).resolve().parents[1] / "docs" / "stacks.md"
# (label, mass ratios, eps, tau ratios): the paper's two drops, then stacks
CASES = [
    ("paper close-up, N = 2", [0.01], 0.9, 0.01),
    ("paper benign, N = 2", [0.05], 0.816, 0.3),
    ("tennis on basketball, N = 2", [0.1], 0.8, 0.1),
    ("N = 3, ratio 0.2", [0.2, 0.2], 0.9, 0.2),
    ("N = 3, ratio 0.05 (Astroblaster-like)", [0.05, 0.05], 0.85, 0.1),
    ("N = 4, ratio 0.3", [0.3] * 3, 0.9, 0.2),
    ("N = 6, ratio 0.5", [0.5] * 5, 0.9, 0.3),
]


def run_times(call, repeats: int) -> list[float]:
    """CPU times of this process over ``repeats`` calls (after one untimed): on two cores shared
    with other work, wall time measures the load as much as the solver."""
    call()
    times = []
    for _ in range(repeats):
        start = time.process_time()
        call()
        times.append(time.process_time() - start)
    return times


def median_time(call, repeats: int) -> float:
    return statistics.median(run_times(call, repeats))


def timings(repeats: int) -> str:
    base = median_time(lambda: twoball.simulate(0.9, 0.2, 0.2), repeats * 10)
    lines = [
        "| balls | linear (exact), ms | / simulate (N = 2) | contact intervals to h2 "
        "| Hertz (compiled), ms (fastest) | Hertz / linear | Hertz (DOP853 reference), ms |",
        "|---|---|---|---|---|---|---|",
    ]
    for balls in (2, 3, 4, 6, 8):
        ratios = [0.2] * (balls - 1)
        linear = median_time(lambda r=ratios: simulate_stack(r, 0.9, 0.2), repeats * 10)
        hertz_times = run_times(
            lambda r=ratios: simulate_stack(r, 0.9, 0.2, force="hertz"),
            repeats * (10 if balls <= 4 else 2),
        )
        hertz = statistics.median(hertz_times)
        reference = "-"
        if balls <= 3:
            seconds = median_time(
                lambda r=ratios: simulate_stack(r, 0.9, 0.2, force="hertz", method="DOP853"), 3
            )
            reference = f"{seconds * 1e3:.0f}"
        intervals = len(simulate_stack(ratios, 0.9, 0.2).contacts)
        lines.append(
            f"| {balls} | {linear * 1e3:.3f} | {linear / base:.1f} | {intervals} "
            f"| {hertz * 1e3:.3f} ({min(hertz_times) * 1e3:.3f}) "
            f"| {hertz / linear:.1f} | {reference} |"
        )
        print(lines[-1], flush=True)
    return (
        "One drop to the top ball's second apex, mass ratio 0.2 between neighbours, eps 0.9, "
        f"gaps 0.2, H = 1e4, median CPU time of repeats, all in one process; `twoball.simulate` "
        f"on the same two-ball drop: {base * 1e3:.3f} ms.\n\n" + "\n".join(lines)
    )


def _moves(args, force: str) -> tuple[float, float]:
    """Relative change of h1 and h2 when H moves by one ulp (1e4 -> its next float)."""
    here = simulate_stack(*args, force=force)
    there = simulate_stack(*args, force=force, height=math.nextafter(1e4, 2e4))

    def change(a, b):
        return abs(a - b) / abs(a) if a and b else float("nan")

    return change(here.h1, there.h1), change(here.h2, there.h2)


def comparison() -> str:
    lines = [
        "| drop | force | h1/chain | h2/h1 | contacts before h1 | h1, h2 move by (1 ulp of H) |",
        "|---|---|---|---|---|---|",
    ]
    for label, ratios, eps, gaps in CASES:
        for force in ("linear", "hertz"):
            r = simulate_stack(ratios, eps, gaps, force=force)
            move1, move2 = _moves((ratios, eps, gaps), force)
            lines.append(
                f"| {label} | {force} | {r.h1 / r.h_icm:.3f} | {r.h2 / r.h1:.3f} | "
                f"{' '.join(str(c) for c in r.contacts_first)} | {move1:.1e}, {move2:.1e} |"
            )
            print(lines[-1], flush=True)
    return "H = 1e4, one eps and one gap for every contact.\n\n" + "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--write", action="store_true", help="write into docs/")
    args = parser.parse_args()
    timing_text = timings(args.repeats)
    comparison_text = comparison()
    if args.write:
        write_section("stacks", timing_text)
        write_section("comparison", comparison_text, STACKS_DOC)


if __name__ == "__main__":
    main()
