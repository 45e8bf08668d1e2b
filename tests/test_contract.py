"""The contract of simulate: status and success, t_eval against dense_output, loud failures."""

import re

import numpy as np
import pytest
from cases import RESTITUTION

import twoball
from twoball import exact
from twoball.errors import ParameterError, SolverError, Status
from twoball.kernels import phases, runs


def test_status_of_a_completed_run_and_of_a_run_that_ends_at_rest():
    done = twoball.simulate(0.9, 0.01, 0.01)
    assert done.status is Status.DONE and done.success and done.reason is None
    rest = twoball.simulate(0.02, 0.3, 0.0, height=100.0)
    assert rest.status is Status.REST and rest.success
    assert rest.reason == Status.REST.message and rest.h2 is None


def test_evaluate_is_the_same_solution_as_t_eval_and_hits_the_apexes():
    times = np.linspace(0.0, 250.0, 57)
    sampled = twoball.simulate(0.816, 0.05, 0.3, t_eval=times).trajectory
    result = twoball.simulate(0.816, 0.05, 0.3, dense_output=True)
    evaluated = result.evaluate(times)
    for name in ("x1", "x2", "v1", "v2", "f01", "f12"):
        np.testing.assert_array_equal(getattr(sampled, name), getattr(evaluated, name))
    # at an apex time the upper ball's velocity is zero and its height the apex height
    at_apex = result.evaluate(result.apex_t)
    np.testing.assert_allclose(at_apex.x2, result.apex_h, rtol=1e-13)
    np.testing.assert_allclose(at_apex.v2, 0.0, atol=1e-9)


def test_evaluate_needs_dense_output():
    with pytest.raises(ValueError, match="dense_output"):
        twoball.simulate(0.9, 0.01, 0.01).evaluate(1.0)


def test_until_a_time_allocates_only_the_apexes_found():
    prepared = phases.prepare(0.05, RESTITUTION[0.816][0], 0.01)
    out = runs.run(1e4, 1.1e4, 2**62, 500.0, prepared, False, False)
    assert out.status == Status.DONE and out.end_time == 500.0
    assert out.apex_t.size == out.apex_h.size < 10


def test_bad_input_is_a_parameter_error_and_a_value_error():
    with pytest.raises(ParameterError, match="mu"):
        twoball.simulate(0.9, -1.0, 0.01)
    assert issubclass(ParameterError, ValueError)
    with pytest.raises(ParameterError, match="t_eval"):
        twoball.simulate(0.9, 0.01, 0.01, t_eval=[0.0, np.nan])


@pytest.mark.parametrize("status", [Status.STUCK, Status.PHASE_LIMIT])
def test_a_stuck_or_limited_run_raises_or_returns_failed(monkeypatch, status):
    real = exact.solve

    def failing(*args, **kwargs):
        return real(*args, **kwargs)._replace(status=status, message=status.message)

    monkeypatch.setitem(twoball.METHODS, "exact", failing)
    with pytest.raises(SolverError, match=re.escape(status.message)) as raised:
        twoball.simulate(0.9, 0.01, 0.01)
    assert raised.value.result.status is status and not raised.value.result.success
    result = twoball.simulate(0.9, 0.01, 0.01, throw=False)
    assert result.status is status and not result.success and result.reason == status.message


def test_the_command_line_reports_a_failed_run_in_one_line_with_status_1(monkeypatch, capsys):
    from twoball.cli import main

    real = exact.solve

    def limited(*args, **kwargs):
        limit = Status.PHASE_LIMIT
        return real(*args, **kwargs)._replace(status=limit, message=limit.message)

    monkeypatch.setitem(twoball.METHODS, "exact", limited)
    assert main(["simulate", "--eps", "0.9", "--mu", "0.01", "--tau-ratio", "0.01"]) == 1
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("twoball: solver failed: exact failed")
    assert lines[0].endswith(Status.PHASE_LIMIT.message)
    assert captured.out == ""


def test_an_apex_above_the_energy_at_release_is_an_error_not_a_value(monkeypatch):
    # H = 1e30 once gave h2 = 4e106 silently (now refused as outside the domain): a solver
    # outcome above the energy bound is a failed run, whatever its status said
    real = exact.solve

    def inflated(*args, **kwargs):
        outcome = real(*args, **kwargs)
        return outcome._replace(apex_h=[outcome.apex_h[0], 1e100])

    monkeypatch.setitem(twoball.METHODS, "exact", inflated)
    with pytest.raises(SolverError, match="impossible") as raised:
        twoball.simulate(0.9, 0.01, 0.01)
    assert raised.value.result.status is Status.IMPOSSIBLE
    monkeypatch.undo()
    # the bound, mu h <= x1(0) + mu x2(0) + 1/2, holds with room on an ordinary drop
    result = twoball.simulate(0.9, 0.01, 0.01, until=3000.0)
    drop = result.drop
    assert result.success and len(result.apex_h) >= 2
    assert max(result.apex_h) < (drop.x1_0 + drop.mu * drop.x2_0 + 0.5) / drop.mu


def test_sample_times_outside_the_run_are_refused_not_extrapolated():
    """t_eval = [-1, 5, 1e9] gave x1 = -5e17 at t = 1e9: a free fall through the floor."""
    with pytest.raises(ParameterError, match="t_eval must hold times >= 0"):
        twoball.simulate(0.9, 0.01, 0.01, t_eval=[-1.0, 5.0])
    result = twoball.simulate(0.9, 0.01, 0.01, dense_output=True)
    span = f"time span [0, {result.end_time:.10g}]"
    with pytest.raises(ParameterError, match=re.escape(span)) as caught:
        twoball.simulate(0.9, 0.01, 0.01, t_eval=[5.0, 1e9])
    assert str(caught.value).startswith("t_eval must lie within")
    with pytest.raises(ParameterError, match=re.escape(span)) as caught:
        result.evaluate([-1.0, 1e9])
    assert str(caught.value).startswith("t must lie within")
    # the end itself is inside: the second apex, as the run found it
    at_end = result.evaluate([0.0, result.end_time])
    assert at_end.x2[1] == pytest.approx(result.h2, rel=1e-12) and at_end.x1[0] == 1e4


def test_after_a_proven_rest_every_later_time_is_that_rest():
    """A run that ends at rest is proven to stay there: later samples are the static rest
    (x1 = -(1 + mu), x2 = x1 - mu; docs/model.md, "Bodies, coordinates, forces")."""
    rest = twoball.simulate(0.02, 0.3, 0.0, height=100.0, t_eval=[1.0, 1e5])
    assert rest.status is Status.REST
    assert rest.trajectory.x1[1] == pytest.approx(-1.3, abs=1e-9)
    assert rest.trajectory.x2[1] == pytest.approx(-1.6, abs=1e-9)


@pytest.mark.parametrize("t_eval", ["abc", [1.0, "2"], [1.0, True]])
def test_sample_times_that_are_not_numbers_name_t_eval(t_eval):
    with pytest.raises(ParameterError, match="t_eval must be a one-dimensional array"):
        twoball.simulate(0.9, 0.01, 0.01, t_eval=t_eval)


@pytest.mark.parametrize(
    ("changed", "named"),
    [
        ({"eps": "0.9"}, "eps"),
        ({"height": "1e4"}, "height"),
        ({"eps": True}, "eps"),
        ({"mu": np.bool_(True)}, "mu"),
        ({"eps12": "0.9"}, "eps12"),
        ({"tau_ratio": b"0.01"}, "tau_ratio"),
    ],
)
def test_text_and_booleans_are_not_numbers(changed, named):
    """eps = '0.9' and height = '1e4' ran, and eps = True ran as 1.0."""
    drop = {"eps": 0.9, "mu": 0.01, "tau_ratio": 0.01} | changed
    with pytest.raises(ParameterError, match=f"^{named} must be a real number"):
        twoball.simulate(**drop)


def test_numpy_numbers_are_numbers():
    plain = twoball.simulate(0.9, 0.01, 0.01, height=1e4)
    numpy = twoball.simulate(
        np.float64(0.9), np.float64(0.01), np.float32(0.01), height=np.int64(10000)
    )
    assert numpy.h2 == twoball.simulate(0.9, 0.01, float(np.float32(0.01))).h2
    assert plain.h1 == pytest.approx(numpy.h1, rel=1e-4)


def test_the_error_vocabulary_is_importable_from_twoball():
    """A caller catches and compares with ``twoball.X``, not ``twoball.errors.X``."""
    import twoball
    from twoball import errors

    assert twoball.Status is errors.Status and twoball.SolverError is errors.SolverError
    with pytest.raises(twoball.ParameterError, match="eps"):
        twoball.simulate(2.0, 0.01, 0.01)
    assert twoball.simulate(0.9, 0.01, 0.01).status is twoball.Status.DONE
