"""One result family: Result and StackResult say how a run ended and what it took alike, pickle
with their dense output, and evaluate either side of a switch."""

import json
import math
import pickle

import numpy as np
import pytest

import twoball
from twoball import ParameterError, SolverError, Status
from twoball.kernels.codes import STATUS_DONE, STATUS_REST
from twoball.observables import BALLS, RunStats


def test_the_errors_and_the_status_are_exported():
    assert twoball.SolverError is SolverError and twoball.Status is Status
    assert twoball.ParameterError is ParameterError


def test_a_status_prints_its_name_and_meaning_and_stays_the_kernels_integer():
    # eps = 0.02: nearly all the energy goes at the first impact, the upper ball never leaves
    answered = twoball.simulate(0.9, 0.01, 0.01)
    at_rest = twoball.simulate(0.02, 0.3, 0.0, height=100.0)
    assert str(answered.status) == f"{answered.status}" == "DONE"
    assert str(at_rest.status) == "REST: the upper ball came to rest on the lower one"
    assert answered.status == STATUS_DONE == 0 and at_rest.status == STATUS_REST == 1
    assert f"{at_rest.status:d}" == "1" and json.dumps(at_rest.status) == "1"
    for status in (answered.status, at_rest.status):
        assert pickle.loads(pickle.dumps(status)) is status


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
    start = next(c.start for c in result.contacts if c.contact == BALLS)
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
    for method in ("compiled", "DOP853"):  # the Hertz force: each contact takes several steps
        hertz = twoball.simulate_stack([0.2], 0.9, 0.2, force="hertz", method=method)
        assert hertz.stats.steps > 3 * len(hertz.contacts) > 0, (method, hertz.stats)
        further = twoball.simulate_stack(
            [0.2], 0.9, 0.2, force="hertz", method=method, until=2 * hertz.end_time
        )
        assert further.stats.steps > hertz.stats.steps


# What Result and StackResult share (twoball.observables.Measured): the same names, the same types
SHARED = (
    "status",
    "reason",
    "success",
    "method",
    "apex_t",
    "apex_h",
    "h1",
    "h2",
    "t1",
    "t2",
    "end_time",
    "contacts",
    "contacts_first",
    "stats",
    "h_icm",
    "x2_0",
    "h1_over_icm",
    "h1_over_drop",
    "h2_over_drop",
    "h2_over_h1",
    "delayed_rebound",
)


def _kind(value):
    """A value's type, into lists and the fields of dataclasses."""
    if isinstance(value, list):
        return ("list", frozenset(_kind(item) for item in value))
    if isinstance(value, RunStats):  # None where a method does not say
        assert all(item is None or type(item) is int for item in value), value
        return RunStats
    if hasattr(value, "__dataclass_fields__"):
        fields = value.__dataclass_fields__
        return (type(value).__name__, tuple((n, type(getattr(value, n))) for n in fields))
    return type(value)


@pytest.fixture(scope="module")
def runs():
    """Real runs with both apexes and a reason of each kind: two balls (exact and a scipy
    method), and stacks of two and three balls with both forces."""
    return {
        "exact": twoball.simulate(0.9, 0.01, 0.01),
        "LSODA": twoball.simulate(0.9, 0.01, 0.01, method="LSODA"),
        "linear pair": twoball.simulate_stack([0.01], 0.9, 0.01),
        "linear three": twoball.simulate_stack([0.5, 0.5], 0.9, 0.1),
        "hertz pair": twoball.simulate_stack([0.1], 0.9, 0.1, force="hertz", height=100.0),
        "hertz three": twoball.simulate_stack([0.5, 0.5], 0.9, 0.1, force="hertz", height=100.0),
        "rest": twoball.simulate(0.02, 0.3, 0.0, height=100.0),
        "stack rest": twoball.simulate_stack([0.3], 0.02, 0.0, height=100.0),
    }


def test_result_and_stack_result_share_their_fields_and_types(runs):
    answered = {name: run for name, run in runs.items() if "rest" not in name}
    for name in SHARED:
        kinds = {run_name: _kind(getattr(run, name)) for run_name, run in answered.items()}
        assert len(set(kinds.values())) == 1, (name, kinds)
    single = runs["exact"]
    assert isinstance(single.contacts_first, list) and single.h2 is not None
    assert all(type(c.contact) is int for run in runs.values() for c in run.contacts)
    assert runs["rest"].reason == runs["stack rest"].reason == Status.REST.message
    assert runs["rest"].h2 is runs["stack rest"].h2 is None


def test_contacts_are_numbered_and_counted_alike_for_two_balls_and_n(runs):
    """contacts_first[c] is the number of intervals of contact c (0 the floor, i ball i on
    i - 1) that start before the first apex: counted here from the intervals themselves; the
    paper's close-up has one floor contact and four ball contacts (docs/model.md)."""
    for name, run in runs.items():
        balls = getattr(getattr(run, "stack", None), "balls", 2)
        first = math.inf if run.t1 is None else run.t1  # at rest with no apex: every contact
        counted = [
            sum(1 for c in run.contacts if c.contact == number and c.start < first)
            for number in range(balls)
        ]
        assert run.contacts_first == counted, name
        assert {c.contact for c in run.contacts} <= set(range(balls)), name
    assert runs["exact"].contacts_first == runs["linear pair"].contacts_first == [1, 4]
    assert runs["LSODA"].contacts_first == [1, 4]


def test_summaries_share_the_observables_keys_and_types(runs):
    """Each summary starts with its model's parameters; the observables after them have the
    same keys and types for every result, and all of it goes through JSON unchanged."""
    measured = list(runs["exact"].measured())
    for name, run in runs.items():
        summary = run.summary()
        assert json.loads(json.dumps(summary)) == summary, name
        assert measured == [key for key in summary if key in measured], name
        assert summary["contacts_first"] == run.contacts_first
    answered = [run for name, run in runs.items() if "rest" not in name]
    for key in measured:
        assert len({_kind(run.summary()[key]) for run in answered}) == 1, key
    assert runs["linear pair"].summary()["method"] == "compiled"
    assert runs["exact"].summary()["h1"] == runs["exact"].h1
    pair = runs["linear pair"].summary()
    assert pair["h1_over_drop"] == pytest.approx(pair["h1"] / pair["x2_0"], rel=1e-15)
    assert pair["h2_over_drop"] == pytest.approx(pair["h2"] / pair["x2_0"], rel=1e-15)


def test_both_trajectories_hold_a_column_per_ball_and_per_contact():
    """x, v and f read alike for two balls and a stack: the pair stack's samples are simulate's
    (the two solvers are independent code, docs/stacks.md)."""
    times = np.linspace(0.0, 300.0, 301)
    single = twoball.simulate(0.9, 0.01, 0.01, t_eval=times).trajectory
    pair = twoball.simulate_stack([0.01], 0.9, 0.01, t_eval=times).trajectory
    for name in ("x", "v", "f"):
        mine, theirs = getattr(single, name), getattr(pair, name)
        assert mine.shape == theirs.shape == (len(times), 2)
        scale = np.abs(theirs).max()
        np.testing.assert_allclose(mine, theirs, rtol=0, atol=1e-9 * scale)
    np.testing.assert_array_equal(single.x[:, 1], single.x2)
    np.testing.assert_array_equal(single.f[:, 0], single.f01)


@pytest.mark.parametrize("method", ["exact", "LSODA"])
def test_dense_output_samples_a_trajectory_only_when_it_is_read(monkeypatch, method):
    """A run with dense output and no t_eval evaluates nothing until its ``trajectory`` is
    read (the app's scenes evaluate at times of their own); then it holds the state at
    ``plot_times`` (for the exact method, times through every contact) as ``evaluate`` gives
    it there, and a pickled result samples the same."""
    result = twoball.simulate(0.816, 0.05, 0.3, method=method, dense_output=True)
    calls = []
    dense = result.dense
    monkeypatch.setattr(result, "dense", lambda t, side="right": calls.append(t) or dense(t, side))
    starts = np.array([c.start for c in result.contacts])
    assert calls == []
    assert method != "exact" or np.all(np.isin(starts, result.plot_times))
    sampled = result.trajectory
    assert len(calls) == 1 and result.trajectory is sampled  # (once)
    expected = result.evaluate(result.plot_times)
    for name in ("t", "x1", "x2", "v1", "v2", "f01", "f12"):
        assert np.array_equal(getattr(sampled, name), getattr(expected, name))
    fresh = twoball.simulate(0.816, 0.05, 0.3, method=method, dense_output=True)
    assert np.array_equal(pickle.loads(pickle.dumps(fresh)).trajectory.x2, sampled.x2)


def test_a_time_outside_the_run_is_quoted_as_given():
    result = twoball.simulate(0.816, 0.05, 0.3, dense_output=True)
    with pytest.raises(ParameterError, match=r"time span \[0, .*\]; got -1 \(run further"):
        result.evaluate(-1.0)
    with pytest.raises(ParameterError, match=r"got times from -1 to 1e\+09"):
        result.evaluate([-1.0, 1e9])
