"""The linear stack against its 40-digit reference (twoball/studies/stack_truth.py;
docs/accuracy.md, "The linear stack")."""

from __future__ import annotations

import csv
from dataclasses import replace
from pathlib import Path

import pytest

CSV = Path(__file__).resolve().parents[1] / "docs" / "stack_vs_truth.csv"


def _stored_references() -> list[dict]:
    with open(CSV, newline="") as handle:
        return list(csv.DictReader(handle))


def _case(row: dict) -> dict:
    return {
        "mass_ratios": [float(r) for r in row["mass_ratios"].split()],
        "eps": float(row["eps"]),
        "tau_ratios": float(row["tau_ratios"]),
        "height": float(row["height"]),
    }


def test_the_table_holds_the_seeded_drops():
    from twoball.studies import stack_truth

    rows = _stored_references()
    cases = stack_truth.cases()
    assert len(rows) == len(cases) >= 20
    assert {int(r["balls"]) for r in rows} == {3, 4, 5, 6}
    for row, case in zip(rows, cases, strict=True):
        assert _case(row) == case


def test_the_kernel_against_the_40_digit_reference():
    """Every drop of docs/stack_vs_truth.csv, the kernel as it is now against the stored
    reference values: equal contact counts and h1 within ten times its stored conditioning on
    all; h2 within it on all but as many drops as the table lists as outside (docs/accuracy.md,
    "The linear stack": drops where one or two ulps of an input move h2 by more than ten times
    its conditioning, so that which of them fall outside changes with any rounding), and on
    those within 100 times, so that a regression shows."""
    from twoball.studies.stack_comparison import stack_against

    stored_rows = _stored_references()
    listed_outside = sum(stored["within"] == "False" for stored in stored_rows)
    outside = 0
    for stored in stored_rows:
        conditioning = (float(stored["cond_h1"]), float(stored["cond_h2"]))
        row = stack_against(_case(stored), stored, conditioning)
        assert row.contacts_first == row.contacts_first_truth, (stored, row)
        assert replace(row, rel_err_h2=0.0).within(), (stored, row)  # h1
        if not row.within():
            outside += 1
            assert row.rel_err_h2 <= 100.0 * row.cond_h2, (stored, row)
    assert outside <= listed_outside <= 3


def test_a_closing_contact_starts_at_zero_overlap():
    """The four-ball drop of the table (eps 0.73, H = 676) against its stored 40-digit h2: its
    top ball lands on the settled stack after ~70 time units in flight, the overlap at that
    root rounded to an ulp of the ~4700 it fell (9.1e-13, docs/accuracy.md, "The linear
    stack"); carried into the contact it put h2 16 times its conditioning off (2.6e-14). Taken
    as exact, h2 is within 2.2 times (3.6e-15)."""
    from twoball.studies.stack_comparison import stack_against

    stored = _stored_references()[5]
    assert (stored["balls"], stored["contacts_first_truth"]) == ("4", "8 13 4 1")
    row = stack_against(_case(stored), stored, (float(stored["cond_h1"]), float(stored["cond_h2"])))
    assert row.rel_err_h2 <= 4.0 * row.cond_h2, row


def test_the_rule_refuses_what_it_should():
    from twoball.studies.stack_comparison import StackComparison

    row = StackComparison("2 3 1", "2 3 1", 1e-15, 9e-15, cond_h1=1e-15, cond_h2=1e-15)
    assert row.within()
    assert not replace(row, rel_err_h2=1.1e-14).within()
    assert not replace(row, contacts_first="3 3 1").within()
    assert replace(row, rel_err_h2=1.1e-14).within(floor=1e-10)  # the Hertz table's floor


def test_the_reference_of_two_balls_is_the_two_ball_reference():
    """N = 2 through the stack reference gives the two-ball 40-digit reference's benign drop
    (docs/exact_vs_truth.csv) to 24 digits: two independent programs."""
    import mpmath

    from twoball.studies import stack_truth

    truth = stack_truth.solve_stack_truth(*stack_truth.inputs([0.05], 0.816, 0.3, 1e4))
    assert truth.contacts_first == [2, 1]
    with mpmath.workdps(40):
        assert abs(truth.h1 / mpmath.mpf("26344.41655112752937669599") - 1) < 1e-24
        assert abs(truth.h2 / mpmath.mpf("19354.27537513962072451229") - 1) < 1e-24


@pytest.mark.slow  # about 10 s
def test_one_reference_value_recomputed():
    """The 40-digit reference recomputes a stored three-ball drop to 24 digits with a step
    of half the size (its answer does not depend on its steps)."""
    import mpmath

    from twoball.studies import stack_truth

    stored = next(r for r in _stored_references() if r["balls"] == "3")
    old = stack_truth.STEP_FRACTION
    stack_truth.STEP_FRACTION = 2 * old
    try:
        fresh = stack_truth.reference(_case(stored))
    finally:
        stack_truth.STEP_FRACTION = old
    assert fresh["contacts_first_truth"] == stored["contacts_first_truth"]
    with mpmath.workdps(40):
        for name in ("h1_truth", "h2_truth"):
            assert abs(mpmath.mpf(fresh[name]) / mpmath.mpf(stored[name]) - 1) < 1e-24


@pytest.mark.parametrize("balls", [3, 4, 6])
def test_the_modes_of_a_closed_stack_to_an_ulp(balls):
    """The block eigenvalues of the grounded cluster of every contact (twoball.kernels.clusters,
    _real_blocks) against mpmath's at 40 digits of the same matrix, light balls on top (ratio
    0.3, eps 0.9): within 2 ulps relative. LAPACK's alone were 5 to 16 ulps off on the slow
    modes (docs/accuracy.md, "The linear stack"), which cost the four-ball drop at H = 1e4 a
    tenth of its h2 digits' worth (1.7e-10 against 1.5e-11)."""
    import mpmath
    import numpy as np

    from twoball.kernels.modes import _real_blocks
    from twoball.stacks import check_stack

    stack = check_stack([0.3] * (balls - 1), 0.9, 0.2)
    m, zeta, k = stack.masses, stack.zeta, balls
    b = np.zeros((2 * k, 2 * k))
    for i in range(k):  # B = [[0, I], [-W, -2 W Z]], W = D M^-1 D^T (docs/stacks.md)
        b[i, k + i] = 1.0
        w_row = np.zeros(k)
        w_row[i] = 1.0 / m[i] + (1.0 / m[i - 1] if i >= 1 else 0.0)
        if i + 1 < k:
            w_row[i + 1] = -1.0 / m[i]
        if i >= 1:
            w_row[i - 1] = -1.0 / m[i - 1]
        b[k + i, :k] = -w_row
        b[k + i, k:] = -w_row * 2.0 * zeta
    _, _, blocks = _real_blocks(b, k)
    with mpmath.workdps(40):
        exact, _ = mpmath.eig(mpmath.matrix(b.tolist()))
        for block in blocks:
            lam = mpmath.mpc(block[0, 0], block[0, 1])
            nearest = min(abs(lam - e) / abs(e) for e in exact)
            assert nearest < 2 * 2.0**-52, (balls, complex(lam), float(nearest))
