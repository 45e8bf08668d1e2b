"""Benchmark: the paper's 50 x 50 x 50 sweep, end to end, on all local cores.

    .venv/bin/python benchmarks/sweep_speed.py [--repeats 3] [--workers N]

Prints the median wall time of a complete ``sweep`` into a fresh Zarr store (store creation,
computing, chunk writes and all, in this process), its cases per second, and two baselines
measured in the same process: the batch path on one core (``compute_block`` on one eps slice),
and ``twoball.simulate`` called once per case on one core. On a shared machine the wall time
depends on what else runs, so the sweep's CPU time (all its threads) is printed too: the rate
the cores would give if the sweep had them to itself.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import tempfile
import time
from pathlib import Path

from perfdoc import write_section  # benchmarks/ is on the path of a script run from it

import twoball
from twoball.batch.sweep import Grid, compute_block, parse_axis, sweep

PAPER = ("0.5:1:50", "0.01:1/3:50", "0.01:1:50")


def paper_grid() -> Grid:
    names = ("eps", "mu", "tau_ratio")
    axes = [parse_axis(name, text) for name, text in zip(names, PAPER, strict=True)]
    return Grid(*axes, dtype="float32")


def _median(times: list[float]) -> float:
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--write", action="store_true", help="update docs/performance.md")
    args = parser.parse_args()
    grid = paper_grid()
    mu, tau_ratio = grid.mu.values(), grid.tau_ratio.values()
    eps_slices = grid.eps.values()[[5, 25, 45]]
    compute_block(eps_slices[:1], mu[:2], tau_ratio[:2])  # load compiled kernels

    # baseline 1: the batch path, one core, three eps slices of the paper's grid
    block_times = []
    for _ in range(args.repeats):
        start = time.perf_counter()
        for eps in eps_slices:
            compute_block([eps], mu, tau_ratio)
        block_times.append(time.perf_counter() - start)
    block_rate = 3 * mu.size * tau_ratio.size / _median(block_times)

    # baseline 2: twoball.simulate once per case, one core, the same three slices thinned
    cases = [(e, m, t) for e in eps_slices for m in mu[::5] for t in tau_ratio[::5]]
    simulate_times, simulate_cpu = [], []
    for _ in range(args.repeats):
        start, cpu = time.perf_counter(), time.process_time()
        for eps, m, t in cases:
            twoball.simulate(eps, m, t)
        simulate_times.append(time.perf_counter() - start)
        simulate_cpu.append(time.process_time() - cpu)
    simulate_rate = len(cases) / _median(simulate_times)
    simulate_per_cpu_second = len(cases) / _median(simulate_cpu)

    # the sweep itself, end to end, into a fresh store each time
    sweep_times, sweep_cpu = [], []
    workdir = Path(tempfile.mkdtemp(prefix="sweep_speed_"))
    try:
        for repeat in range(args.repeats):
            store = workdir / f"paper{repeat}.zarr"
            start, cpu = time.perf_counter(), time.process_time()
            sweep(grid, store, workers=args.workers, progress=False)
            sweep_times.append(time.perf_counter() - start)
            sweep_cpu.append(time.process_time() - cpu)
            shutil.rmtree(store)
    finally:
        shutil.rmtree(workdir, ignore_errors=True)
    wall = _median(sweep_times)
    workers = args.workers or os.cpu_count()
    per_cpu_second = grid.size / _median(sweep_cpu)
    lines = [
        f"paper grid {grid.size} cases (50 x 50 x 50, H = 1e4), {workers} threads",
        f"sweep, end to end     median {wall:7.2f} s of {args.repeats} "
        f"({', '.join(f'{t:.2f}' for t in sweep_times)}): {grid.size / wall:8.0f} cases/s",
        f"sweep, CPU time       median {_median(sweep_cpu):7.2f} s: {per_cpu_second:8.0f} cases "
        f"per CPU-second: at most {workers * per_cpu_second:.0f} cases/s on {workers} idle cores",
        f"batch path, one core  {block_rate:8.0f} cases/s (compute_block, 3 eps slices)",
        f"simulate, one core    {simulate_rate:8.0f} cases/s (one call per case), "
        f"{simulate_per_cpu_second:.0f} per CPU-second",
        f"ratios: sweep / simulate loop {grid.size / wall / simulate_rate:.2f} "
        f"(by CPU time, on idle cores: {workers * per_cpu_second / simulate_per_cpu_second:.2f}), "
        f"batch / simulate {block_rate / simulate_rate:.2f}; "
        f"target < 120 s: {'met' if wall < 120 else 'MISSED'}",
    ]
    print("\n".join(lines))
    if args.write:
        write_section("sweep", "```\n" + "\n".join(lines) + "\n```")


if __name__ == "__main__":
    main()
