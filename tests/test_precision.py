"""Work-precision (twoball.studies.precision) and the 40-digit reference (twoball.studies.truth)."""

from __future__ import annotations

import csv
import math
from dataclasses import asdict

import mpmath
import pytest
from cases import BENIGN

import twoball
from twoball.cli import main
from twoball.observables import relative_error
from twoball.studies import precision
from twoball.studies.truth import solve_truth


@pytest.fixture(scope="module")
def benign_rows() -> list[precision.PrecisionRow]:
    return precision.work_precision(*BENIGN.drop, tolerances=(1e-3, 1e-9))


def test_rows_follow_the_contract(benign_rows):
    methods = [row.method for row in benign_rows]
    assert methods == ["exact"] + [m for m in precision.METHODS[1:] for _ in range(2)]
    for row in benign_rows:
        assert set(asdict(row)) == set(precision.COLUMNS)
        assert (row.tolerance is None) == (row.method == "exact")
        assert math.isfinite(row.seconds) and row.seconds > 0.0
    exact = benign_rows[0]
    assert exact.rel_err_h1 == 0.0 and exact.rel_err_h2 == 0.0


def test_errors_are_against_the_model_values_and_shrink_with_the_tolerance(benign_rows):
    # the check values of docs/model.md, "What is measured", independent of the exact solver: at
    # 1e-9 every scipy method
    # agrees with them to 1e-6, and its error is far below its error at 1e-3
    for method in precision.METHODS[1:]:
        loose, tight = (r for r in benign_rows if r.method == method)
        assert tight.rel_err_h1 < 1e-5 and tight.rel_err_h2 < 1e-5, method
        assert max(loose.rel_err_h1, loose.rel_err_h2) > 30 * max(
            tight.rel_err_h1, tight.rel_err_h2
        )
        result = twoball.simulate(*BENIGN.drop, method=method, rtol=1e-9, atol=1e-9)
        assert abs(result.h1 - BENIGN.h1) / BENIGN.h1 < 2e-9 + tight.rel_err_h1


def test_a_failing_method_gives_infinite_errors_not_an_exception(monkeypatch):
    real = precision.simulate

    def failing(*args, method="exact", **kwargs):
        if method == "BDF":
            raise ArithmeticError("Newton iteration diverged")
        return real(*args, method=method, **kwargs)

    monkeypatch.setattr(precision, "simulate", failing)
    rows = precision.work_precision(*BENIGN.drop, methods=("exact", "BDF"), tolerances=(1e-6,))
    assert rows[1].method == "BDF"
    assert rows[1].rel_err_h1 == math.inf and rows[1].rel_err_h2 == math.inf


def test_no_second_bounce_gives_nan_for_h2():
    # eps = 0.05 is overdamped: the upper ball comes to rest after one bounce
    assert twoball.simulate(0.05, 0.01, 0.5).h2 is None
    rows = precision.work_precision(0.05, 0.01, 0.5, methods=("exact", "LSODA"), tolerances=(1e-8,))
    assert all(math.isnan(row.rel_err_h2) for row in rows)
    assert rows[1].rel_err_h1 < 1e-5


def test_relative_error_says_which_side_lacks_the_bounce():
    assert relative_error(3.3, 3.0) == pytest.approx(0.1)
    assert relative_error(None, 3.0) == math.inf  # missed
    assert relative_error(5.0, None) == math.inf  # invented
    assert math.isnan(relative_error(None, None))  # nobody has it


def test_bad_input_names_the_parameter():
    with pytest.raises(ValueError, match="eps"):
        precision.work_precision(1.5, 0.05, 0.3)
    with pytest.raises(ValueError, match="methods"):
        precision.work_precision(*BENIGN.drop, methods=("Euler",))
    with pytest.raises(ValueError, match="tolerances"):
        precision.work_precision(*BENIGN.drop, tolerances=(0.0,))


def test_csv_and_png(benign_rows, tmp_path):
    precision.write_csv(benign_rows, tmp_path / "wp.csv")
    with open(tmp_path / "wp.csv") as handle:
        read = list(csv.DictReader(handle))
    assert tuple(read[0]) == precision.COLUMNS
    assert len(read) == len(benign_rows) and read[0]["tolerance"] == ""
    precision.plot_work_precision(benign_rows, tmp_path / "wp.png")
    data = (tmp_path / "wp.png").read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000


def test_command_line_bad_input_is_one_line(capsys, tmp_path):
    assert main(["precision", "--out", str(tmp_path), "--repeats", "0"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "repeats" in err


# --- the 40-digit reference ---------------------------------------------------------------


@pytest.fixture(scope="module")
def benign_truth():
    return solve_truth(*BENIGN.drop)


def test_truth_locates_the_first_floor_contact_at_the_closed_form_time(benign_truth):
    # the lower ball falls freely from H: it touches the floor at sqrt(2 H) exactly
    floor = [c for c in benign_truth.contacts if c[0] == 0]
    with mpmath.workdps(40):
        assert abs(floor[0][1] - mpmath.sqrt(2 * mpmath.mpf(1e4))) < mpmath.mpf(10) ** -30


def test_truth_agrees_with_the_model_check_values(benign_truth):
    assert abs(float(benign_truth.h1) - BENIGN.h1) < 1e-4
    assert abs(float(benign_truth.h2) - BENIGN.h2) < 1e-4


def test_exact_solver_against_truth(benign_truth):
    """Within ten times the drop's conditioning (twoball.studies.conditioning)."""
    from twoball.studies.conditioning import against_reference, within_rule

    truth = benign_truth
    # its floor and ball contacts, numbered as a Result's: the same as the exact solver's
    assert truth.contacts_first == twoball.simulate(*BENIGN.drop).contacts_first == [2, 1]
    row = against_reference(*BENIGN.drop, truth.h1, truth.h2, truth.contacts_first[1])
    assert within_rule(row), row
    assert row.contacts_first == 1


def test_the_documented_cases_meet_the_rule():
    """The exact solver as it is now on the five cases of docs/exact_vs_truth.csv (docs/accuracy.md,
    section 1), against the 40-digit values stored there, within ten times their conditioning
    measured afresh."""
    import csv
    from pathlib import Path

    from twoball.studies.conditioning import against_reference, within_rule
    from twoball.studies.precision import CASES

    path = Path(__file__).resolve().parents[1] / "docs" / "exact_vs_truth.csv"
    with open(path) as handle:
        stored = {row["case"]: row for row in csv.DictReader(handle)}
    assert set(stored) == set(CASES)
    for case, drop in CASES.items():
        reference = stored[case]
        row = against_reference(
            *drop, reference["h1_truth"], reference["h2_truth"], reference["contacts_first_truth"]
        )
        assert within_rule(row), (case, row)


@pytest.mark.slow
def test_truth_does_not_depend_on_its_step(monkeypatch):
    # H = 100 keeps it quick; halving every step must not move the answer beyond 1e-25
    from twoball.studies import truth

    first = truth.solve_truth(*BENIGN.drop, height=100.0)
    monkeypatch.setattr(truth, "STEP_FRACTION", 2 * truth.STEP_FRACTION)
    monkeypatch.setattr(truth, "FREE_FLIGHT_STEP", truth.FREE_FLIGHT_STEP / 3)
    second = truth.solve_truth(*BENIGN.drop, height=100.0)
    with mpmath.workdps(40):
        assert abs(first.h1 - second.h1) / first.h1 < mpmath.mpf(10) ** -25
        assert abs(first.h2 - second.h2) / first.h2 < mpmath.mpf(10) ** -25


def test_truth_rejects_bad_input_like_the_library():
    with pytest.raises(ValueError, match="mu"):
        solve_truth(0.9, -1.0, 0.3)


def test_truth_can_nudge_the_state_at_the_first_apex():
    """A nudge of X2 at the first apex leaves h1 alone and moves h2 smoothly: twice the nudge,
    twice the move (what benchmarks/state_conditioning.py measures, docs/accuracy.md)."""
    drop = dict(height=100.0)
    plain = solve_truth(*BENIGN.drop, **drop)
    once = solve_truth(*BENIGN.drop, nudge=(1, 2**20), **drop)
    twice = solve_truth(*BENIGN.drop, nudge=(1, 2**21), **drop)
    with mpmath.workdps(40):
        assert once.h1 == plain.h1 == twice.h1
        step = math.ulp(float(plain.h1))  # the nudge is in ulps of X2 there, which is h1
        first, second = once.h2 - plain.h2, twice.h2 - plain.h2
        assert abs(first) > 2**19 * step * 1e-3  # it moved h2 (by a fair share of the nudge)
        assert abs(second / first - 2) < 1e-3


def test_truth_can_round_the_heights_at_every_switch():
    """Half-ulp roundings of x1, x2 at the switches before the first apex move h1 by a few
    ulps at most on a benign drop (one ball contact), never not at all, and the same seed
    gives the same run (benchmarks/state_conditioning.py --switches, docs/accuracy.md)."""
    drop = dict(height=100.0)
    plain = solve_truth(*BENIGN.drop, **drop)
    once = solve_truth(*BENIGN.drop, round_heights=1, **drop)
    again = solve_truth(*BENIGN.drop, round_heights=1, **drop)
    with mpmath.workdps(40):
        moved = abs((once.h1 - plain.h1) / plain.h1)
        assert 0 < moved < 1e-13
        assert once.h1 == again.h1 and once.h2 == again.h2
