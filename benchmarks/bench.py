"""Benchmark: the exact solver against LSODA as the paper used it (``twoball bench``), written
into docs/performance.md.

    python benchmarks/bench.py [--cases 50] [--seed 0] [--repeats 5] [--write]
"""

from __future__ import annotations

import argparse

from perfdoc import write_section  # benchmarks/ is on the path of a script run from it

from twoball.studies.bench import benchmark


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=50)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--write", action="store_true", help="update docs/performance.md")
    args = parser.parse_args()
    figures = benchmark(args.cases, args.seed, args.repeats)
    eps, mu, tau_ratio = figures["worst_case"]
    text = f"""{args.cases} random points of the paper's cube (seed {args.seed}, H = 1e4), each run
to the second apex in one process; medians of {args.repeats} repeats.

| | median per case |
| --- | --- |
| exact solver | {figures["exact_median_s"] * 1e3:.3f} ms |
| LSODA as the paper used it (`odeint`, rtol = atol = 1e-8, grid step 0.01) | \
{figures["lsoda_median_s"] * 1e3:.1f} ms |
| speed-up | **{figures["speedup_median"]:.0f}x median, \
{figures["speedup_min"]:.0f}x on the slowest case** |

Accuracy: the exact solver and DOP853 at rtol = atol = 1e-12 agree to \
{figures["exact_vs_dop853_max"]:.1e} on all cases; where they differ most (eps {eps:.4g}, \
mu {mu:.4g}, tau_ratio {tau_ratio:.4g}) the 40-digit reference puts the exact solver \
{figures["worst_exact_vs_truth"]:.1e} from the truth and DOP853 \
{figures["worst_dop853_vs_truth"]:.1e}. LSODA on the paper's grid is off by \
{figures["lsoda_vs_exact_median"]:.1e} (median)."""
    if "cvode_median_s" in figures:
        text += f"""

CVODE (SUNDIALS BDF with root finding, rtol = atol = 1e-12, its tightest useful tolerance):
median {figures["cvode_median_s"] * 1e3:.1f} ms per case, so the exact solver is \
{figures["cvode_speedup_median"]:.0f}x faster (median); CVODE's relative error in h1 and h2 is \
{figures["cvode_vs_exact_median"]:.1e} (median), {figures["cvode_vs_exact_max"]:.1e} at worst."""
    print(text)
    if args.write:
        write_section("bench", text)


if __name__ == "__main__":
    main()
