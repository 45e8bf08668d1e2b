"""A/B timing of the compiled Hertz kernel: this tree's against another revision's, in one process.

    .venv/bin/python benchmarks/hertz_ab.py --base REVISION [--rounds 5]

(0e1a585 is the last revision with the compiled DOP853, before the Taylor series.)

The other revision's twoball/kernels/hertz.py and taylor.py (``git show``; they must run on
this tree's lower kernel modules) are loaded beside this tree's under other names, and both run
the documented drops (benchmarks/stacks.py: mass ratio 0.2 between neighbours, eps 0.9, gaps
0.2, H = 1e4, to the top ball's second apex) on the same inputs, alternating kernel by kernel
within each round, so that both are measured under the same load. Prints each round's median
CPU time per drop and the median over the rounds, with each kernel's steps and h1, h2.
"""

from __future__ import annotations

import argparse
import importlib.util
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from twoball.kernels import hertz as this_kernel
from twoball.stacks import check_stack, hertz

HERE = Path(__file__).resolve().parents[1]
BALLS = ((2, 40), (3, 20), (6, 3))  # (balls, repeats per round)


def load_base(revision: str):
    """The kernel module of ``revision``, imported under another name, with its own Taylor
    series module (taylor.py, under another name too)."""
    folder = Path(tempfile.mkdtemp(prefix="hertz-base-"))
    for name in ("taylor", "hertz"):
        source = subprocess.run(
            ["git", "show", f"{revision}:twoball/kernels/{name}.py"],
            cwd=HERE,
            capture_output=True,
            text=True,
            check=True,
        ).stdout
        source = source.replace("from twoball.kernels.taylor import", "from taylor_base import")
        path = folder / f"{name}_base.py"
        path.write_text(source)
        spec = importlib.util.spec_from_file_location(f"{name}_base", path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[f"{name}_base"] = module
        spec.loader.exec_module(module)
    return module


def inputs(balls: int) -> tuple:
    """The arguments of ``run`` for the documented drop of ``balls`` balls (as
    twoball.stacks.hertz.solve_compiled makes them)."""
    stack = check_stack([0.2] * (balls - 1), 0.9, 0.2, height=1e4, force="hertz")
    eps = np.asarray(stack.eps, dtype=float)
    lam = np.array([hertz.damping_factor(float(e)) for e in eps])
    lam /= hertz.calibration_speeds(stack.masses, eps, stack.height)
    return stack.masses, lam, stack.x_start, 2, np.inf, np.empty(0)


def median_time(call, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.process_time()
        call()
        times.append(time.process_time() - start)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--base", required=True, help="the other revision (e.g. 0e1a585)")
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    kernels = {"base": load_base(args.base), "this": this_kernel}
    for balls, _ in BALLS:
        for name, kernel in kernels.items():
            run = kernel.run(*inputs(balls))
            top = run[2][run[2][:, 0] == balls - 1, 2]
            print(
                f"N = {balls} {name}: steps {run[6]}, h1 {float(top[0])!r}, h2 {float(top[1])!r}",
                flush=True,
            )
    medians = {(name, balls): [] for name in kernels for balls, _ in BALLS}
    for round_ in range(args.rounds):
        line = []
        for balls, repeats in BALLS:
            arguments = inputs(balls)
            for name, kernel in kernels.items():
                seconds = median_time(lambda k=kernel, a=arguments: k.run(*a), repeats)
                medians[name, balls].append(seconds)
                line.append(f"N = {balls} {name} {seconds * 1e3:.3f} ms")
        print(f"round {round_ + 1}: " + ", ".join(line), flush=True)
    for balls, _ in BALLS:
        base = statistics.median(medians["base", balls])
        this = statistics.median(medians["this", balls])
        print(
            f"N = {balls}: base {base * 1e3:.3f} ms, this {this * 1e3:.3f} ms ({this / base:.2f})"
        )


if __name__ == "__main__":
    main()
