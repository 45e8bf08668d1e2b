"""Accuracy of the linear stack: the compiled kernel (twoball.kernels.stack) against the 40-digit
mpmath reference (twoball/studies/stack_truth.py) on seeded drops of 3 to 6 balls.

    .venv/bin/python benchmarks/stack_accuracy.py [--recompute] [--write]

The reference values are read from docs/stack_vs_truth.csv (``--recompute``: computed again,
a few minutes). Prints one row per drop: the kernel's relative errors in h1 and h2, the drop's
conditioning (the larger of the secant over 2^16 ulps of every input with the kernel, summed, as
for two balls, and the reference's own move when H moves by one ulp: docs/accuracy.md, "The
linear stack"), the error over the conditioning, and the contacts before h1 (kernel /
reference). The references at the moved H are read from the CSV too, computed where missing.
``--write`` rewrites docs/stack_vs_truth.csv and the table of docs/accuracy.md ("The linear
stack").
"""

from __future__ import annotations

import argparse
import csv
import time
from dataclasses import asdict
from pathlib import Path

from perfdoc import write_section  # benchmarks/ is on the path of a script run from it

from twoball.studies import stack_truth
from twoball.studies.stack_comparison import stack_against

DOCS = Path(__file__).resolve().parents[1] / "docs"
CSV = DOCS / "stack_vs_truth.csv"
REFERENCE_COLUMNS = ("h1_truth", "h2_truth", "contacts_first_truth")
MOVED_COLUMNS = ("height_moved", "h1_truth_moved", "h2_truth_moved")


def stored() -> list[dict]:
    with open(CSV, newline="") as handle:
        return list(csv.DictReader(handle))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--recompute", action="store_true", help="recompute the references")
    parser.add_argument("--write", action="store_true", help="write into docs/")
    args = parser.parse_args()
    cases = stack_truth.cases()
    old = None if args.recompute or not CSV.exists() else stored()
    rows = []
    for i, case in enumerate(cases):
        start = time.perf_counter()
        if old is None:
            reference = stack_truth.reference(case)
        else:
            reference = {k: old[i][k] for k in REFERENCE_COLUMNS}
        if old is not None and all(k in old[i] for k in MOVED_COLUMNS):
            reference.update({k: old[i][k] for k in MOVED_COLUMNS})
        else:
            reference.update(stack_truth.moved_reference(case))
            print(f"{i:2d} moved: {[reference[k] for k in MOVED_COLUMNS]}", flush=True)
        seconds = time.perf_counter() - start
        row = {
            "balls": len(case["mass_ratios"]) + 1,
            "mass_ratios": " ".join(repr(r) for r in case["mass_ratios"]),
            "eps": repr(case["eps"]),
            "tau_ratios": repr(case["tau_ratios"]),
            "height": repr(case["height"]),
            **reference,
        }
        compared = stack_against(case, reference, stack_truth.conditioning(case, reference))
        row.update(asdict(compared))
        row["ratio"] = max(row["rel_err_h1"] / row["cond_h1"], row["rel_err_h2"] / row["cond_h2"])
        secant = stack_truth.conditioning(case)
        row["secant_h1"], row["secant_h2"] = float(secant[0]), float(secant[1])
        moved = stack_truth.one_ulp_move(reference)
        row["moved_h1"], row["moved_h2"] = float(moved[0]), float(moved[1])
        row["within"] = compared.within()
        rows.append(row)
        print(
            f"{i:2d} N={row['balls']} eps={case['eps']:.3f} H={case['height']:.3g}: "
            f"h1 {row['rel_err_h1']:.1e} h2 {row['rel_err_h2']:.1e} "
            f"(cond {row['cond_h1']:.1e}, {row['cond_h2']:.1e}; ratio {row['ratio']:.2f}; "
            f"secant {row['secant_h2']:.1e}, reference moved {row['moved_h2']:.1e}) "
            f"contacts {row['contacts_first']} / {row['contacts_first_truth']} {row['within']}"
            + ("" if old is not None else f" (reference {seconds:.0f} s)"),
            flush=True,
        )
    print(summary(rows))
    if args.write:
        with open(CSV, "w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
            writer.writeheader()
            for row in rows:
                writer.writerow(
                    {k: (f"{v:.3e}" if isinstance(v, float) else v) for k, v in row.items()}
                )
        write_section("stack-accuracy", table(rows), DOCS / "accuracy.md")


def summary(rows: list[dict]) -> str:
    worst = max(max(r["rel_err_h1"], r["rel_err_h2"]) for r in rows)
    worst_h1 = max(r["rel_err_h1"] for r in rows)
    ratios = sorted(r["ratio"] for r in rows)
    held = sum(bool(r["within"]) for r in rows)
    same = sum(r["contacts_first"] == r["contacts_first_truth"] for r in rows)
    return (
        f"{len(rows)} seeded drops (`twoball.studies.stack_truth.cases`). Contact counts equal "
        f"on {same} of {len(rows)}; the kernel's largest error in h1 is {worst_h1:.1e}, in h1 "
        f"or h2 {worst:.1e}; error / conditioning at most {ratios[-1]:.1f} (median "
        f"{ratios[len(ratios) // 2]:.1f}); the rule (equal contact counts, each error within "
        f"ten times the conditioning) holds on {held} of {len(rows)}."
    )


def table(rows: list[dict]) -> str:
    lines = [
        "| N | mass ratios | eps | gap | H | h2 (40-digit reference) | rel. error h1 | h2 "
        "| cond_h1 | cond_h2 | of which: secant (2^16 ulps, kernel) | one ulp of H (reference) "
        "| error / cond | contacts before h1 (kernel / reference) | within the rule |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        ratios = ", ".join(f"{float(x):.3g}" for x in r["mass_ratios"].split())
        lines.append(
            f"| {r['balls']} | {ratios} | {float(r['eps']):.3g} | {float(r['tau_ratios']):.3g} "
            f"| {float(r['height']):.3g} | {r['h2_truth'][:16]} | {r['rel_err_h1']:.1e} "
            f"| {r['rel_err_h2']:.1e} | {r['cond_h1']:.1e} | {r['cond_h2']:.1e} "
            f"| {r['secant_h2']:.1e} | {r['moved_h2']:.1e} | {r['ratio']:.2f} "
            f"| {r['contacts_first']} / {r['contacts_first_truth']} "
            f"| {'yes' if r['within'] else '**no**'} |"
        )
    return summary(rows) + "\n\n" + "\n".join(lines)


if __name__ == "__main__":
    main()
