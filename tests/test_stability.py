"""Stiff and extreme cases (twoball.studies.stability): a fast subset of the study."""

from __future__ import annotations

import dataclasses
import itertools
import math
import time

import numpy as np
import pytest

import twoball
from twoball.cli import main
from twoball.observables import BALLS
from twoball.studies import stability

# A fast subset of the study's grid: its extreme values, all combinations (32 cases).
EXTREMES = list(
    itertools.product(
        (0.02, stability.EPS_BRANCH_SWITCH, 0.999999, 1.0), (1e-6, 1e2), (0.0, 10.0), (1.0, 1e8)
    )
)


def _energy(result):
    t = result.trajectory
    return stability.energy(t.x1, t.x2, t.v1, t.v2, result.drop.mu)


def test_grid_spans_the_issue_ranges():
    assert min(stability.GRID["mu"]) == 1e-6 and max(stability.GRID["mu"]) == 1e2
    assert {0.02, math.exp(-2.0), 0.999999, 1.0} <= set(stability.GRID["eps"])
    assert min(stability.GRID["tau_ratio"]) == 0.0 and max(stability.GRID["tau_ratio"]) == 10.0
    assert min(stability.GRID["height"]) == 1.0 and max(stability.GRID["height"]) == 1e8


def test_energy_is_conserved_without_damping():
    # eps = 1: no dashpots, so the energy (docs/model.md, "Bodies, coordinates, forces": spring
    # potentials) is a constant
    result = twoball.simulate(1.0, 0.05, 0.3, dense_output=True)
    energy = _energy(result)
    drop = result.drop
    assert energy[0] == pytest.approx(drop.x1_0 + drop.mu * drop.x2_0, rel=1e-15)
    assert np.max(np.abs(energy - energy[0])) / energy[0] < 1e-12


def test_energy_never_rises_and_is_dissipated_with_damping():
    result = twoball.simulate(0.816, 0.05, 0.3, dense_output=True)
    energy = _energy(result)
    t = result.trajectory
    rounding = stability.energy_rounding(t.x1, t.x2, t.v1, t.v2, 0.05, 2 * len(result.contacts) + 3)
    assert np.all(np.diff(energy) <= rounding[1:] + rounding[:-1])
    assert energy[-1] < 0.9 * energy[0]


def test_compression_bound_holds_and_is_reached_with_equal_elastic_balls():
    # equal masses, no damping: at the balls' collision the centre of mass is nearly at rest, so
    # nearly all the energy sits in the ball spring and the overlap nearly reaches the bound
    result = twoball.simulate(1.0, 1.0, 1.0, height=1e8, dense_output=True)
    t = result.trajectory
    bound = stability.max_compression(1.0, result.drop.x1_0, result.drop.x2_0)
    deepest = -np.min(t.x2 - t.x1)
    assert 0.99 * bound < deepest <= bound


@pytest.mark.parametrize(
    "case", EXTREMES, ids=lambda c: "eps={:.6g}-mu={:g}-tau={:g}-H={:g}".format(*c)
)
def test_exact_solver_on_extreme_cases(case):
    row = stability.judge(stability.diagnose(*case, "exact", 0.0), None)
    assert row.finished
    assert row.verdict == "right", row.problems
    values = [v for v in (row.h1, row.h2) if v is not None]
    assert all(math.isfinite(v) for v in values)
    assert len(values) == 2 or "rest" in row.reason


def _doctored(monkeypatch, change):
    """Make diagnose see the exact solver's benign run, changed by ``change(result)``."""
    real = stability.simulate

    def doctored(*args, **kwargs):
        return change(real(*args, **kwargs))

    monkeypatch.setattr(stability, "simulate", doctored)
    return stability.diagnose(0.816, 0.05, 0.3, 1e4, "exact", 0.0)


def test_a_ball_passing_through_is_detected(monkeypatch):
    def sink(result):
        t = result.trajectory
        later = t.t > t.t[len(t.t) // 2]
        x2 = np.where(later, t.x1 - 1e3, t.x2)  # the upper ball sinks 1000 below the lower one
        return dataclasses.replace(result, trajectory=dataclasses.replace(t, x2=x2))

    row = _doctored(monkeypatch, sink)
    assert {"passed through", "energy gained", "missed ball contact"} <= set(row.problems)


def test_an_unreported_contact_is_detected(monkeypatch):
    def forget(result):
        kept = [c for c in result.contacts if c.contact != BALLS]
        return dataclasses.replace(result, contacts=kept)

    row = _doctored(monkeypatch, forget)
    assert row.problems == ["missed ball contact"]


def test_a_small_energy_gain_is_detected(monkeypatch):
    def pump(result):
        t = result.trajectory
        v2 = t.v2 * (1.0 + 1e-9 * (t.t > t.t[-1] / 2))  # 1e-9 more speed after half the run
        return dataclasses.replace(result, trajectory=dataclasses.replace(t, v2=v2))

    row = _doctored(monkeypatch, pump)
    assert row.problems == ["energy gained"]


def test_missed_contacts_of_an_adaptive_method_are_detected():
    # eps = 1, mu = 1e-6, balls touching at release: 64 brief ball contacts before the second
    # apex; DOP853 at 1e-12, a method independent of the exact solver, counts them too
    case = (1.0, 1e-6, 0.0, 1e4)
    exact = stability.diagnose(*case, "exact", 0.0)
    tight = twoball.simulate(*case[:3], method="DOP853", rtol=1e-12, atol=1e-12)
    assert sum(c.contact == BALLS for c in tight.contacts) == len(exact.contact_starts) == 64
    row = stability.judge(stability.diagnose(*case, "RK45", 1e-8), exact)
    assert row.verdict == "wrong"
    assert "missed ball contact" in row.problems
    assert row.ball_contacts < row.exact_ball_contacts == 64


def _slow_diagnose(*task):
    time.sleep(60)


def test_a_run_over_the_cap_is_killed_and_reported_too_slow():
    started = time.monotonic()
    rows = stability.study(
        [],
        [(0.816, 0.05, 0.3, 1e4)],
        methods=("LSODA",),
        cap=1.0,
        workers=1,
        diagnose_one=_slow_diagnose,  # imported by name in the spawned worker
    )
    assert time.monotonic() - started < 55  # below the 60 s the task sleeps: it was killed
    assert rows[0].verdict == "too slow" and rows[0].method == "LSODA"


def test_study_runs_every_method_in_workers():
    case = (0.816, 0.05, 0.3, 1e4)
    rows = stability.study(
        [case], [case], methods=("exact", "LSODA", "DOP853"), workers=2, check=("DOP853", 1e-10)
    )
    assert [r.method for r in rows] == ["exact", "LSODA", "DOP853", "DOP853 1e-10"]
    assert all(r.verdict == "right" for r in rows)
    assert rows[1].rel_err_h1 < 1e-5 and rows[1].exact_ball_contacts == 2
    assert rows[3].ball_contacts == 2 and rows[3].rel_err_h2 < 1e-7


def test_h_convergence_matches_model_md():
    # docs/model.md, "Initial condition", on H: eps = 0.816, mu = 0.05, tau_d/tau_f = 0.3
    rows = stability.h_convergence([(0.816, 0.05, 0.3)], (1e2, 1e3, 1e4, 1e5, 1e6))
    ratios = [row.h2_over_h1 for row in rows]
    assert ratios == pytest.approx([1.399, 0.868, 0.7347, 0.695, 0.683], abs=6e-4)
    icm = [row.h1_over_icm for row in rows]
    assert icm == pytest.approx([0.567, 0.574, 0.5760, 0.5765, 0.5766], abs=6e-4)


def test_command_line_bad_input_is_one_line(capsys, tmp_path):
    assert main(["stability", "--out", str(tmp_path), "--cap", "-1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cap" in err
