"""Random stacks over the tested domain: how many finish, and which fail (always loudly).

    .venv/bin/python benchmarks/stack_search.py [--domain bench|wide] [--drops 100000]
        [--seconds 240] [--seed 3] [--write]

Two domains, each run to the top ball's second apex with the linear force:

- ``bench``: real balls stacked on a bench, damped: 3 to 8 balls, mass ratios 10^U(log 0.005,
  log 0.5), eps U(0.3, 0.7), a gap U(0, 0.05) of a floor contact, H = 10^U(0, 2).
- ``wide``: 2 to 8 balls, mass ratios 10^U(-2, 1), eps U(0.3, 1) or 1 one time in five, a gap
  of 0 one time in seven else U(0, 1.5), H = 10^U(1, 6).

Stops after ``--drops`` in-domain stacks or ``--seconds``, whichever comes first, and prints the
count that finished and every failure. Inputs refused with a ParameterError (the domain's limits)
are not counted. ``--write`` puts the summary into docs/performance.md.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
from perfdoc import write_section  # benchmarks/ is on the path of a script run from it

from twoball.errors import ParameterError
from twoball.stacks import simulate_stack


def draw_bench(rng: np.random.Generator) -> tuple[list[float], float, float, float]:
    balls = int(rng.integers(3, 9))
    ratios = list(10 ** rng.uniform(math.log10(0.005), math.log10(0.5), balls - 1))
    return ratios, rng.uniform(0.3, 0.7), rng.uniform(0.0, 0.05), 10 ** rng.uniform(0.0, 2.0)


def draw_wide(rng: np.random.Generator) -> tuple[list[float], float, float, float]:
    ratios = list(10 ** rng.uniform(-2, 1, rng.integers(1, 8)))
    eps = rng.uniform(0.3, 1.0) if rng.random() < 0.8 else 1.0
    gap = 0.0 if rng.random() < 1 / 7 else rng.uniform(0, 1.5)
    return ratios, eps, gap, 10 ** rng.uniform(1, 6)


DOMAINS = {"bench": draw_bench, "wide": draw_wide}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--domain", choices=sorted(DOMAINS), default="wide")
    parser.add_argument("--drops", type=int, default=100_000)
    parser.add_argument("--seconds", type=float, default=240.0)
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--write", action="store_true", help="update docs/performance.md")
    args = parser.parse_args()
    draw = DOMAINS[args.domain]
    rng = np.random.default_rng(args.seed)
    simulate_stack([0.2, 0.2], 0.5, 0.01)  # compile outside the clock
    failures, finished, ended, start = [], 0, {}, time.perf_counter()
    while finished + len(failures) < args.drops and time.perf_counter() - start < args.seconds:
        ratios, eps, gap, height = draw(rng)
        try:
            result = simulate_stack(ratios, eps, gap, height=height, throw=False)
        except ParameterError:
            continue
        ended[result.status.name] = ended.get(result.status.name, 0) + 1
        if result.success:
            finished += 1
        else:
            failures.append((len(ratios) + 1, eps, gap, height, result.status.name))
            print("failed:", failures[-1], flush=True)
    seconds = time.perf_counter() - start
    tried = finished + len(failures)
    endings = ", ".join(f"{count} {name}" for name, count in sorted(ended.items()))
    summary = (
        f"domain {args.domain}, seed {args.seed}: {tried} in-domain stacks ({endings}), "
        f"{len(failures)} failed, {seconds:.0f} s ({tried / seconds:,.0f} stacks/s)"
    )
    print(summary)
    for balls, eps, gap, height, status in failures:
        print(f"  {balls} balls, eps {eps:.3f}, gap {gap:.3g}, H {height:.3g}: {status}")
    if args.write:
        listed = "".join(f"\n- failed: {failure}" for failure in failures)
        write_section(f"stack-search-{args.domain}", summary + listed)


if __name__ == "__main__":
    main()
