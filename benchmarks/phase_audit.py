"""Where the exact solver loses accuracy, phase by phase (docs/accuracy.md, "Many-contact drops").

Runs one drop with its phases recorded, then propagates each phase's start state exactly (40 digits,
``mpmath.expm`` of the phase's matrix from twoball.studies.truth, which shares no code with
twoball/kernels/phases.py) over the phase's own duration, and prints the solver's end state against
that, in ulps of each coordinate's size over the phase (the larger of its start and end values):
the phase's local error. The coordinates are the solver's (docs/model.md, "Bodies, coordinates,
forces"): the lower ball's height and speed, the overlap eta = X2 - X1 and its rate. A closing
switch sets its overlap to zero (twoball.kernels.runs.run), so the error printed for eta at such a
switch is what that removed.

    .venv/bin/python benchmarks/phase_audit.py EPS MU TAU_RATIO [--height 1e4]
"""

from __future__ import annotations

import argparse
import math

import mpmath
import numpy as np

from twoball.kernels import phases, runs
from twoball.model import check_parameters
from twoball.studies.truth import _phase_matrix

KINDS = {phases.FREE: "free", phases.FLOOR: "floor", phases.BALL: "ball", phases.BOTH: "both"}
NAMES = ("x1", "eta", "v1", "eta'")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("eps", type=float)
    parser.add_argument("mu", type=float)
    parser.add_argument("tau_ratio", type=float)
    parser.add_argument("--height", type=float, default=1e4)
    args = parser.parse_args()
    drop = check_parameters(args.eps, args.mu, args.tau_ratio, height=args.height)
    prepared = phases.prepare(drop.mu, drop.zeta01, drop.zeta12)
    out = runs.run(drop.x1_0, drop.x2_0, 2, np.inf, prepared, False, True)
    print(f"{out.phases.shape[0]} phases; apexes {out.apex_h.tolist()}")
    print("   t         phase  tau        local error, ulps: " + "  ".join(NAMES))
    with mpmath.workdps(40):
        mu, z01, z12 = (mpmath.mpf(v) for v in (drop.mu, drop.zeta01, drop.zeta12))
        matrices = {}
        worst = np.zeros(4)
        for start, end in zip(out.phases[:-1], out.phases[1:], strict=True):
            t, kind, x1, eta, v1, deta, tau = start
            kind = int(kind)
            if kind not in matrices:
                matrices[kind] = _phase_matrix(bool(kind & 1), bool(kind & 2), mu, z01, z12)
            x1_, eta_, v1_, deta_ = (mpmath.mpf(v) for v in (x1, eta, v1, deta))
            y = mpmath.matrix([x1_, x1_ + eta_, v1_, v1_ + deta_, 1])
            moved = mpmath.expm(matrices[kind] * mpmath.mpf(tau)) * y
            exact_end = (moved[0], moved[1] - moved[0], moved[2], moved[3] - moved[2])
            errors = []
            for index, value in enumerate(exact_end):
                size = max(abs(start[2 + index]), abs(float(value)))
                ulp = math.ulp(size) if size > 0 else math.ulp(0.0)
                errors.append(float(end[2 + index] - value) / ulp)
            worst = np.maximum(worst, np.abs(errors))
            cells = "  ".join(f"{e:7.1f}" for e in errors)
            print(f"{t:11.4f}  {KINDS[kind]:>5}  {tau:.3e}  {cells}")
    print("largest: " + ", ".join(f"{n} {w:.1f}" for n, w in zip(NAMES, worst, strict=True)))


if __name__ == "__main__":
    main()
