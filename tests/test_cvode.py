"""CVODE, the optional peer (twoball.cvode): docs/model.md's check values to its tolerance, its
error falling with the tolerance, a clear refusal where it has nothing to give, and a failure
said in the result, not printed."""

import ctypes

import pytest
from cases import BENIGN, CLOSE_UP, CLOSE_UP_CONTACTS

import twoball
from twoball import Status
from twoball.observables import BALLS

pytest.importorskip("sksundae", reason="the cvode extra (scikit-sundae) is not installed")


@pytest.mark.parametrize("case", [CLOSE_UP, BENIGN], ids=["close-up", "benign"])
def test_cvode_reproduces_the_check_values_of_the_model(case):
    result = twoball.simulate(*case.drop, method="CVODE", rtol=1e-10, atol=1e-10)
    assert result.method == "CVODE" and result.success and result.reason is None
    # the check values carry 9 digits; CVODE at 1e-10 is good to ~1e-7 relative on these
    assert result.h1 == pytest.approx(case.h1, rel=2e-7)
    assert result.h2 == pytest.approx(case.h2, rel=2e-7)
    if case is CLOSE_UP:
        assert result.contacts_first[BALLS] == CLOSE_UP_CONTACTS


def test_cvode_error_falls_with_its_tolerance():
    exact = twoball.simulate(*CLOSE_UP.drop)
    errors = [
        abs(twoball.simulate(*CLOSE_UP.drop, method="CVODE", rtol=t, atol=t).h2 - exact.h2)
        for t in (1e-5, 1e-11)
    ]
    assert errors[1] < errors[0] / 100


def test_cvode_refuses_dense_output_in_words():
    with pytest.raises(ValueError, match="CVODE gives no dense output"):
        twoball.simulate(*CLOSE_UP.drop, method="CVODE", dense_output=True)


def _printed_at_fd_level(capfd) -> tuple[str, str]:
    """What reached file descriptors 1 and 2, C's buffered stdio included."""
    ctypes.CDLL(None).fflush(None)
    return capfd.readouterr()


def test_a_failing_cvode_run_says_why_in_its_result_and_prints_nothing(capfd):
    # rtol = atol = 1e-17 is below what double precision can give: CVODE gives up at t = 0
    result = twoball.simulate(*CLOSE_UP.drop, method="CVODE", rtol=1e-17, atol=1e-17, throw=False)
    assert not result.success and result.status == Status.FAILED
    assert "too much accuracy requested" in result.reason
    assert _printed_at_fd_level(capfd) == ("", "")


def test_sundials_warnings_stay_off_the_terminal(capfd):
    # At H = 1e8 the first impact comes at t ~ 14142, where steps of ~1e-13 are below the
    # time's resolution: SUNDIALS warns "t + h = t on the next step" on C's stdout
    result = twoball.simulate(
        0.816, 1e-6, 0.1, height=1e8, method="CVODE", rtol=1e-13, atol=1e-13, until=14143.5
    )
    assert result.contacts_first[0] == 1  # the run went through the impact
    assert _printed_at_fd_level(capfd) == ("", "")


def test_the_benchmark_counts_cvodes_failures_apart():
    """`twoball bench` gives CVODE's times and errors over the runs it finished and says how
    many it did not: a failed run (its h2 missing, an error of inf) had gone into the median
    time and made the largest error "inf", with no word of why (2 of 50 at rtol 1e-12, a
    researcher's run)."""
    from twoball.studies.bench import _cvode_figures

    rows = [
        {"cvode_failed": False, "cvode_s": 0.2, "exact_s": 1e-4, "cvode_vs_exact": 1e-9},
        {"cvode_failed": False, "cvode_s": 0.4, "exact_s": 1e-4, "cvode_vs_exact": 3e-9},
        {"cvode_failed": True, "cvode_s": 9.0, "exact_s": 1e-4, "cvode_vs_exact": float("inf")},
    ]
    figures = _cvode_figures(rows)
    assert figures["cvode_failed"] == 1
    assert figures["cvode_median_s"] == pytest.approx(0.3)
    assert figures["cvode_vs_exact_max"] == pytest.approx(3e-9)
