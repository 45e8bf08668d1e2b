"""A/B timing of the linear stack kernel: this tree against another copy of the sources.

    git archive BASE_COMMIT | tar -x -C /tmp/base
    .venv/bin/python benchmarks/stack_ab.py /tmp/base [--rounds 3]

Times the documented drops (benchmarks/stacks.py: mass ratio 0.2 between neighbours, eps 0.9,
gaps 0.2, H = 1e4, to the top ball's second apex) with three and eight balls: median CPU time of
repeats in one process per tree and round, the trees alternating, so that both are measured
under the same load. Prints each round and the median over the rounds.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]
CHILD = r"""
import json, statistics, sys, time
sys.path.insert(0, sys.argv[1])
from twoball.stacks import simulate_stack
def median(call, repeats):
    call()
    times = []
    for _ in range(repeats):
        start = time.process_time()
        call()
        times.append(time.process_time() - start)
    return statistics.median(times)
out = {}
for balls, repeats in ((3, 70), (8, 7)):
    ratios = [0.2] * (balls - 1)
    out[balls] = median(lambda: simulate_stack(ratios, 0.9, 0.2), repeats) * 1e3
print(json.dumps(out))
"""


def measure(tree: Path) -> dict:
    done = subprocess.run(
        [sys.executable, "-c", CHILD, str(tree)],
        capture_output=True,
        text=True,
        check=True,
        cwd="/",
    )
    return {int(k): v for k, v in json.loads(done.stdout.strip().splitlines()[-1]).items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("base", type=Path, help="the other tree's root (holding twoball/)")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    results: dict[str, list[dict]] = {"base": [], "this": []}
    for _ in range(args.rounds):
        for name, tree in (("base", args.base), ("this", HERE)):
            results[name].append(measure(tree))
            print(name, results[name][-1], flush=True)
    for name, rows in results.items():
        medians = {b: statistics.median(r[b] for r in rows) for b in (3, 8)}
        print(f"{name}: 3 balls {medians[3]:.3f} ms, 8 balls {medians[8]:.1f} ms")


if __name__ == "__main__":
    main()
