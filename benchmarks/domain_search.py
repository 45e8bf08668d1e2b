"""Random drops inside the domain (docs/model.md, "The domain double precision can carry"):
how many does the exact solver fail on, and which?

    python benchmarks/domain_search.py --seed 11 --drops 1000000 --eps 0.01:1

Draws eps (uniform in the range given), eps12 (= eps half the time, else uniform in [0.01, 1]),
mu log-uniform in [1e-9, 1e6], tau_ratio 0 a fifth of the time, else log-uniform in [1e-4, 1e2],
and H log-uniform in [1e-3, 1e12]; drops outside the domain are skipped. Prints each failure
(a stated one: the solver never fails silently) and a summary line.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from perfdoc import write_section

import twoball
from twoball.errors import ParameterError
from twoball.model import check_parameters


def search(seed: int, drops: int, eps_range: tuple[float, float]) -> tuple[int, list[tuple]]:
    """(in-domain drops tried, failures as (eps, mu, tau_ratio, eps12, H, status))."""
    rng = np.random.default_rng(seed)
    tried, failures = 0, []
    for _ in range(drops):
        eps = rng.uniform(*eps_range)
        eps12 = eps if rng.random() < 0.5 else rng.uniform(0.01, 1.0)
        mu = 10 ** rng.uniform(-9, 6)
        tau_ratio = 0.0 if rng.random() < 0.2 else 10 ** rng.uniform(-4, 2)
        height = 10 ** rng.uniform(-3, 12)
        try:
            check_parameters(eps, mu, tau_ratio, eps12=eps12, height=height)
        except ParameterError:
            continue
        tried += 1
        result = twoball.simulate(eps, mu, tau_ratio, eps12=eps12, height=height, throw=False)
        if not result.success:
            failures.append((eps, mu, tau_ratio, eps12, height, result.status.name))
            print("failed:", failures[-1], flush=True)
    return tried, failures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=11)
    parser.add_argument("--drops", type=int, default=100_000)
    parser.add_argument("--eps", default="0.01:1", help="LOW:HIGH of eps")
    parser.add_argument("--write", action="store_true", help="update docs/performance.md")
    args = parser.parse_args()
    low, high = (float(part) for part in args.eps.split(":"))
    twoball.simulate(0.9, 0.01, 0.01)  # compile outside the clock
    started = time.perf_counter()
    tried, failures = search(args.seed, args.drops, (low, high))
    seconds = time.perf_counter() - started
    summary = (
        f"seed {args.seed}, eps in [{low}, {high}]: {tried} in-domain drops, "
        f"{len(failures)} failed (stated), {seconds:.0f} s ({tried / seconds:,.0f} drops/s)"
    )
    print(summary)
    if args.write:
        listed = "".join(f"\n- failed: {failure}" for failure in failures)
        write_section(f"domain-eps-{low:g}-{high:g}", summary + listed)


if __name__ == "__main__":
    main()
