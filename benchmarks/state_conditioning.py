"""The many-contact drops' sensitivity to the rounding of the state (docs/accuracy.md).

For the drops of docs/many_contacts.csv whose error is furthest above their input conditioning,
runs the 40-digit reference twice: as it is, and with the upper ball's height moved by one
double ulp at its first apex; prints the table of docs/accuracy.md, "Many-contact drops"
(about a minute a drop on one core). With ``--switches DROP`` (1 for the first row), it runs
that drop's reference with the heights rounded to double at every switch of the first
collision instead, three seeds (the paragraph after the table).

    .venv/bin/python benchmarks/state_conditioning.py [--drops 6] [--switches 6]
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import mpmath

from twoball.studies.truth import solve_truth

SAMPLE = Path(__file__).resolve().parents[1] / "docs" / "many_contacts.csv"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--drops", type=int, default=6)
    parser.add_argument("--switches", type=int, default=None, metavar="DROP")
    args = parser.parse_args()
    rows = list(csv.DictReader(SAMPLE.open()))

    def excess(row: dict) -> float:
        return max(float(row[f"rel_err_{h}"]) / float(row[f"cond_{h}"]) for h in ("h1", "h2"))

    rows.sort(key=excess, reverse=True)
    if args.switches is not None:
        row = rows[args.switches - 1]
        drop = tuple(float(row[k]) for k in ("eps", "mu", "tau_ratio"))
        plain = solve_truth(*drop)
        print(
            f"drop {drop}: exact solver off by {row['rel_err_h1']} in h1, {row['rel_err_h2']} in h2"
        )
        for seed in (1, 2, 3):
            rounded = solve_truth(*drop, round_heights=seed)
            with mpmath.workdps(40):
                pairs = zip(rounded.apex_h, plain.apex_h, strict=True)
                moved = [abs(float((r - p) / p)) for r, p in pairs]
            print(f"  heights rounded at each switch, seed {seed}: h1 moves {moved[0]:.1e}, "
                  f"h2 {moved[1]:.1e}", flush=True)  # fmt: skip
        return
    print("| drop (eps, mu, tau_d/tau_f) | h2 error | cond_h2 (inputs) "
          "| h2 moved by 1 ulp of X2 at the first apex | error / that |")  # fmt: skip
    print("|---|---|---|---|---|")
    for row in rows[: args.drops]:
        drop = tuple(float(row[k]) for k in ("eps", "mu", "tau_ratio"))
        h2 = solve_truth(*drop).h2
        moved = solve_truth(*drop, nudge=(1, 1)).h2
        with mpmath.workdps(40):
            state = abs(float((moved - h2) / h2))
        error, cond = float(row["rel_err_h2"]), float(row["cond_h2"])
        print(
            f"| {drop[0]:.3f}, {drop[1]:.2e}, {drop[2]:.2e} | {error:.1e} | {cond:.1e} "
            f"| {state:.1e} ({state / cond:.3g} x cond_h2) | {error / state:.3g} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
