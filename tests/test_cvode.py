"""CVODE, the optional peer (twoball.cvode): docs/model.md's check values to its tolerance, its
error falling with the tolerance, and a clear refusal where it has nothing to give."""

import pytest
from cases import BENIGN, CLOSE_UP, CLOSE_UP_CONTACTS

import twoball
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
