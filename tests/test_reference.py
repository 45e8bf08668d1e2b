"""The scipy reference integrators: same equations, same result type, agreement when benign."""

import pytest

import twoball
from twoball.reference import METHODS


@pytest.mark.parametrize("method", METHODS)
def test_reference_methods_agree_with_exact_on_a_benign_case(method):
    exact = twoball.simulate(0.816, 0.05, 0.3, height=1e2)
    options = {} if method == "odeint" else {"rtol": 1e-10, "atol": 1e-10}
    result = twoball.simulate(0.816, 0.05, 0.3, height=1e2, method=method, **options)
    assert isinstance(result, twoball.Result) and result.method == method
    assert result.reason is None
    # odeint reads apexes off a grid of step 0.01: its error is set by the grid, not by rtol
    tolerance = 1e-4 if method == "odeint" else 1e-6
    assert result.h1 == pytest.approx(exact.h1, rel=tolerance)
    assert result.h2 == pytest.approx(exact.h2, rel=tolerance)
    assert result.t1 == pytest.approx(exact.t1, abs=0.01 if method == "odeint" else 1e-5)
    assert result.contacts_first == exact.contacts_first


def test_reference_dense_output_has_the_same_shape_as_exact():
    result = twoball.simulate(0.816, 0.05, 0.3, height=1e2, method="DOP853", dense_output=True)
    tr = result.trajectory
    assert tr.t.shape == tr.x1.shape == tr.f12.shape
    assert tr.t[0] == 0.0 and tr.x1[0] == 1e2


def test_a_loose_tolerance_is_worse_than_a_tight_one():
    exact = twoball.simulate(0.9, 0.01, 0.01, height=1e3)
    errors = []
    for tol in (1e-4, 1e-10):
        result = twoball.simulate(0.9, 0.01, 0.01, height=1e3, method="RK45", rtol=tol, atol=tol)
        errors.append(abs(result.h1 - exact.h1) / exact.h1)
    assert errors[1] < errors[0]


def test_a_method_is_named_in_any_case():
    """ "cvode" (as its extra is called) or "dop853" name the same solver as METHODS does; a
    name that is none of them is still refused with the list."""
    lower = twoball.simulate(0.9, 0.01, 0.01, method="dop853", rtol=1e-8, atol=1e-8)
    named = twoball.simulate(0.9, 0.01, 0.01, method="DOP853", rtol=1e-8, atol=1e-8)
    assert lower.method == "DOP853" and (lower.h1, lower.h2) == (named.h1, named.h2)
    with pytest.raises(ValueError, match="method must be one of exact, LSODA"):
        twoball.simulate(0.9, 0.01, 0.01, method="euler")
