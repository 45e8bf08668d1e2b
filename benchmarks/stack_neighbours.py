"""The linear stack kernel's error on neighbouring inputs: H = 1e4 plus 0 to 7 ulps, against the
40-digit reference (twoball/studies/stack_truth.py), for a two-, three- and four-ball drop.

    .venv/bin/python benchmarks/stack_neighbours.py

A table of seeded drops (benchmarks/stack_accuracy.py) sees the kernel at one input each; a
change of rounding (docs/accuracy.md, "The linear stack", what was tried) can help there and
hurt one ulp away. Prints the relative errors of h1 and h2 at each input (about two minutes).
"""

from __future__ import annotations

import math

import mpmath

from twoball.stacks import simulate_stack
from twoball.studies import stack_truth

DROPS = (
    ("two balls", [0.05], 0.816, 0.3),
    ("three balls", [0.2, 0.2], 0.9, 0.2),
    ("four balls", [0.3] * 3, 0.9, 0.2),
)
ULPS = range(8)


def main() -> None:
    for label, ratios, eps, gap in DROPS:
        for k in ULPS:
            height = 1e4 + k * math.ulp(1e4)
            truth = stack_truth.solve_stack_truth(*stack_truth.inputs(ratios, eps, gap, height))
            result = simulate_stack(ratios, eps, gap, height=height)
            with mpmath.workdps(40):
                errors = [
                    float(abs(mpmath.mpf(mine) / exact - 1))
                    for mine, exact in ((result.h1, truth.h1), (result.h2, truth.h2))
                ]
            print(f"{label}, H = 1e4 + {k} ulp: h1 {errors[0]:.1e}, h2 {errors[1]:.1e}", flush=True)


if __name__ == "__main__":
    main()
