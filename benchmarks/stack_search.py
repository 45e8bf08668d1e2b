"""Random stacks over the tested domain: how many finish, and which fail (always loudly).

    .venv/bin/python benchmarks/stack_search.py [--seconds 240] [--seed 3]

Draws stacks of 2 to 8 balls (mass ratios 10^U(-2, 1), eps U(0.3, 1) or 1 one time in five,
a gap of 0 one time in seven else U(0, 1.5), H = 10^U(1, 6)), runs each to the top ball's
second apex with the linear force and prints the count that finished and every failure.
Inputs refused with a ParameterError (the domain's limits) are not counted.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from twoball.errors import ParameterError
from twoball.stack import simulate_stack


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=240.0)
    parser.add_argument("--seed", type=int, default=3)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    failures, finished, start = [], 0, time.perf_counter()
    while time.perf_counter() - start < args.seconds:
        ratios = list(10 ** rng.uniform(-2, 1, rng.integers(1, 8)))
        eps = rng.uniform(0.3, 1.0) if rng.random() < 0.8 else 1.0
        gap = 0.0 if rng.random() < 1 / 7 else rng.uniform(0, 1.5)
        height = 10 ** rng.uniform(1, 6)
        try:
            result = simulate_stack(ratios, eps, gap, height=height, throw=False)
        except ParameterError:
            continue
        if result.success:
            finished += 1
        else:
            failures.append((len(ratios) + 1, eps, gap, height, result.status.name))
    print(f"{finished} stacks finished, {len(failures)} failed")
    for balls, eps, gap, height, status in failures:
        print(f"  {balls} balls, eps {eps:.3f}, gap {gap:.3g}, H {height:.3g}: {status}")


if __name__ == "__main__":
    main()
