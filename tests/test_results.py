"""One result family: Result and StackResult say how a run ended and what it took alike, pickle
with their dense output, and evaluate either side of a switch."""

import pickle

import numpy as np
import pytest

import twoball
from twoball import ParameterError, SolverError, Status
from twoball.observables import RunStats


def test_the_errors_and_the_status_are_exported():
    assert twoball.SolverError is SolverError and twoball.Status is Status
    assert twoball.ParameterError is ParameterError


@pytest.mark.parametrize("method", ["exact", "LSODA", "odeint"])
def test_a_result_with_dense_output_pickles_and_evaluates_the_same(method):
    result = twoball.simulate(0.9, 0.01, 0.01, method=method, dense_output=True)
    copy = pickle.loads(pickle.dumps(result))
    assert copy.summary() == result.summary() and copy.contacts == result.contacts
    assert copy.stats == result.stats
    times = np.linspace(0.0, result.end_time, 1013)
    for side in ("left", "right"):
        original, restored = result.evaluate(times, side=side), copy.evaluate(times, side=side)
        for name in ("x1", "x2", "v1", "v2", "f01", "f12"):
            np.testing.assert_array_equal(getattr(restored, name), getattr(original, name))


def test_left_and_right_of_a_switch_differ_as_the_closed_form_says():
    """At a ball contact's start the overlap is zero, so the force jumps from 0 (left, free
    flight) to the dashpot's -2 zeta12 eta' (right, docs/model.md, "Bodies, coordinates,
    forces"); the heights and speeds are continuous."""
    result = twoball.simulate(0.9, 0.01, 0.01, dense_output=True)
    start = next(c.start for c in result.contacts if c.contact == "ball")
    left = result.evaluate(start, side="left")
    right = result.evaluate(start, side="right")
    closing = right.v2[0] - right.v1[0]
    assert closing < 0.0 and left.f12[0] == 0.0
    assert right.f12[0] == pytest.approx(-2.0 * result.drop.zeta12 * closing, rel=1e-12)
    for name in ("x1", "x2", "v1", "v2"):
        assert getattr(left, name)[0] == pytest.approx(getattr(right, name)[0], rel=1e-9, abs=1e-9)
    # away from a switch both sides are the same state
    inside = 0.5 * (start + result.contacts[0].end)
    np.testing.assert_array_equal(
        result.evaluate(inside, side="left").f12, result.evaluate(inside).f12
    )
    with pytest.raises(ParameterError, match="side"):
        result.evaluate(start, side="middle")


def test_run_statistics_are_on_the_result():
    plain = twoball.simulate(0.9, 0.01, 0.01)
    dense = twoball.simulate(0.9, 0.01, 0.01, dense_output=True)
    assert isinstance(plain.stats, RunStats) and plain.stats == dense.stats
    assert plain.stats.steps >= plain.stats.phases > len(plain.contacts)
    assert plain.stats.root_evaluations >= 1
    reference = twoball.simulate(0.9, 0.01, 0.01, method="LSODA")
    assert reference.stats.phases >= 2 and reference.stats.steps > reference.stats.phases
    stack = twoball.simulate_stack([0.01], 0.9, 0.01)
    assert stack.stats.phases >= len(stack.contacts) > 0


def test_result_and_stack_result_share_their_names():
    single = twoball.simulate(0.9, 0.01, 0.01)
    pair = twoball.simulate_stack([0.01], 0.9, 0.01)
    for name in ("status", "reason", "success", "apex_t", "apex_h", "h1", "h2", "end_time"):
        assert hasattr(single, name) and hasattr(pair, name), name
    assert pair.reason is single.reason is None
    assert pair.apex_h == pytest.approx(single.apex_h, rel=1e-9)
    shared = {"h1", "h2", "contacts_first", "status", "reason"}
    assert shared <= set(single.summary()) & set(pair.summary())
    rest = twoball.simulate_stack([0.3], 0.02, 0.0, height=100.0)
    assert rest.status is Status.REST and rest.reason == Status.REST.message
