"""Accuracy of the Hertz stack: the compiled path and the DOP853 reference method against the
30-digit mpmath reference (twoball/studies/hertz_truth.py) on seeded drops.

    .venv/bin/python benchmarks/hertz_accuracy.py [--recompute] [--write]

The reference values are read from docs/hertz_vs_truth.csv (``--recompute``: computed again,
about three minutes). Prints one row per drop: the compiled path's relative errors in h1 and h2,
the drop's conditioning, DOP853's errors, and the contacts before h1 (compiled / reference).
``--write`` rewrites docs/hertz_vs_truth.csv and the Hertz table of docs/accuracy.md.
"""

from __future__ import annotations

import argparse
import csv
from dataclasses import asdict
from pathlib import Path

from perfdoc import write_section  # benchmarks/ is on the path of a script run from it

from twoball.studies import hertz_truth
from twoball.studies.stack_comparison import stack_against

DOCS = Path(__file__).resolve().parents[1] / "docs"
CSV = DOCS / "hertz_vs_truth.csv"
REFERENCE_COLUMNS = ("h1_truth", "h2_truth", "contacts_first_truth")


def stored() -> list[dict]:
    with open(CSV, newline="") as handle:
        return list(csv.DictReader(handle))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--recompute", action="store_true", help="recompute the references")
    parser.add_argument("--write", action="store_true", help="write into docs/")
    args = parser.parse_args()
    cases = hertz_truth.cases()
    old = None if args.recompute or not CSV.exists() else stored()
    rows = []
    for i, case in enumerate(cases):
        if old is None:
            reference = hertz_truth.reference(case)
        else:
            reference = {k: old[i][k] for k in REFERENCE_COLUMNS}
        row = {
            "balls": len(case["mass_ratios"]) + 1,
            "mass_ratios": " ".join(repr(r) for r in case["mass_ratios"]),
            "eps": repr(case["eps"]),
            "tau_ratios": repr(case["tau_ratios"]),
            "height": repr(case["height"]),
            **reference,
        }
        conditioning = hertz_truth.conditioning(case)
        compiled = stack_against(case, reference, conditioning, force="hertz")
        row.update(asdict(compiled))
        dop853 = stack_against(case, reference, conditioning, force="hertz", method="DOP853")
        row["dop853_rel_err_h1"] = dop853.rel_err_h1
        row["dop853_rel_err_h2"] = dop853.rel_err_h2
        row["dop853_contacts_first"] = dop853.contacts_first
        row["within"] = compiled.within(floor=hertz_truth.TOLERANCE_H)
        rows.append(row)
        print(
            f"{i:2d} N={row['balls']} eps={case['eps']:.3f} H={case['height']:.3g}: "
            f"h1 {row['rel_err_h1']:.1e} h2 {row['rel_err_h2']:.1e} "
            f"(cond {row['cond_h1']:.1e}, {row['cond_h2']:.1e}; DOP853 "
            f"{row['dop853_rel_err_h1']:.1e}, {row['dop853_rel_err_h2']:.1e}) contacts "
            f"{row['contacts_first']} / {row['contacts_first_truth']} {row['within']}",
            flush=True,
        )
    if args.write:
        with open(CSV, "w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
            writer.writeheader()
            for row in rows:
                writer.writerow(
                    {k: (f"{v:.3e}" if isinstance(v, float) else v) for k, v in row.items()}
                )
        write_section("hertz-accuracy", table(rows), DOCS / "accuracy.md")


def table(rows: list[dict]) -> str:
    lines = [
        "| N | mass ratios | eps | gap | H | h2 (30-digit reference) | compiled: rel. error h1 "
        "| h2 | cond_h1 | cond_h2 | DOP853: rel. error h1 | h2 | contacts before h1 "
        "(compiled / reference) | within the rule |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        ratios = ", ".join(f"{float(x):.3g}" for x in r["mass_ratios"].split())
        lines.append(
            f"| {r['balls']} | {ratios} | {float(r['eps']):.3g} | {float(r['tau_ratios']):.3g} "
            f"| {float(r['height']):.3g} | {r['h2_truth'][:16]} | {r['rel_err_h1']:.1e} "
            f"| {r['rel_err_h2']:.1e} | {r['cond_h1']:.1e} | {r['cond_h2']:.1e} "
            f"| {r['dop853_rel_err_h1']:.1e} | {r['dop853_rel_err_h2']:.1e} "
            f"| {r['contacts_first']} / {r['contacts_first_truth']} "
            f"| {'yes' if r['within'] else '**no**'} |"
        )
    worst = max(max(r["rel_err_h1"], r["rel_err_h2"]) for r in rows)
    worst_dop853 = max(max(r["dop853_rel_err_h1"], r["dop853_rel_err_h2"]) for r in rows)
    held = sum(bool(r["within"]) for r in rows)
    worst_h1 = max(r["rel_err_h1"] for r in rows)
    same = sum(r["contacts_first"] == r["contacts_first_truth"] for r in rows)
    return (
        f"{len(rows)} seeded drops (`twoball.studies.hertz_truth.cases`). Contact counts equal "
        f"on {same} of {len(rows)}; the compiled path's largest error in h1 is {worst_h1:.1e}, "
        f"in h1 or h2 {worst:.1e} (DOP853's: {worst_dop853:.1e}); the rule (equal contact "
        f"counts, each error within 1e-10 or ten times the conditioning, whichever is larger) "
        f"holds on {held} of {len(rows)}.\n\n" + "\n".join(lines)
    )


if __name__ == "__main__":
    main()
