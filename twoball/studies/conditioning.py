"""How well a drop is posed in double precision, and the accuracy rule measured against it.

A drop's conditioning (cond_h1, cond_h2) is how far h1 and h2 move, relative, when one input
(eps, mu, tau_ratio, H) moves by one ulp, summed over the inputs: the least error any solver
handed those inputs as doubles can promise. Each term is a central difference over
DIFFERENCE_ULPS ulps, wide enough that the exact solver's own rounding, divided by the step, is
far below the derivative.

The rule (docs/accuracy.md, section 1): the same contacts as the 40-digit reference, and each of
h1, h2 within TOLERANCE and within CONDITIONING_FACTOR times its conditioning.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from twoball.model import DEFAULT_HEIGHT
from twoball.observables import BALLS, relative_error
from twoball.solve import simulate

DIFFERENCE_ULPS = 2.0**16
TOLERANCE = 2e-10  # h1 and h2 within this of the reference, relative
CONDITIONING_FACTOR = 10.0  # and within this many times their conditioning
REFERENCE_DIGITS = 25  # a reference height stored as text (40 digits computed)


@dataclass(frozen=True)
class Comparison:
    """The exact solver against a reference on one drop (:func:`against_reference`), what
    :func:`within_rule` judges: the ball contacts before the first apex of both, the relative
    errors in h1 and h2 (inf: a bounce missed or invented; NaN: neither has it) and the drop's
    conditioning. The studies' rows extend it (:class:`~twoball.studies.precision.TruthRow`,
    :class:`~twoball.studies.many_contacts.ManyContactsRow`)."""

    contacts_first: int
    contacts_first_truth: int
    rel_err_h1: float
    rel_err_h2: float
    cond_h1: float
    cond_h2: float


def _heights(eps: float, mu: float, tau_ratio: float, height: float) -> np.ndarray:
    result = simulate(eps, mu, tau_ratio, height=height)
    return np.array([result.h1, result.h2])


def conditioning(
    eps: float, mu: float, tau_ratio: float, *, height: float = DEFAULT_HEIGHT
) -> np.ndarray:
    """(cond_h1, cond_h2): relative move of h1 and h2 per one-ulp move of each input, summed."""
    base = _heights(eps, mu, tau_ratio, height)
    inputs = [eps, mu, tau_ratio, height]
    total = np.zeros(2)
    for index, value in enumerate(inputs):
        if value == 0.0:
            continue
        step = DIFFERENCE_ULPS * math.ulp(value)
        up = min(value + step, 1.0) if index == 0 else value + step  # eps stays in (0, 1]
        down = value - step
        args_up, args_down = list(inputs), list(inputs)
        args_up[index], args_down[index] = up, down
        slope = (_heights(*args_up) - _heights(*args_down)) / (up - down)
        total += np.abs(slope) * math.ulp(value) / np.abs(base)
    return total


def against_reference(
    eps: float,
    mu: float,
    tau_ratio: float,
    h1,
    h2,
    contacts_first: int,
    *,
    height: float = DEFAULT_HEIGHT,
) -> Comparison:
    """What :func:`within_rule` judges, for the exact solver as it is now on one drop: its ball
    contacts in the first bounce and relative errors in h1 and h2 against reference values (the
    40-digit reference's numbers, or their text as :func:`reference_text` stores them), and the
    drop's conditioning."""
    import mpmath

    result = simulate(eps, mu, tau_ratio, height=height)
    cond = conditioning(eps, mu, tau_ratio, height=height)
    with mpmath.workdps(40):  # text of 25 digits is read at full precision
        references = [None if h in (None, "") else mpmath.mpf(h) for h in (h1, h2)]
        errors = [
            relative_error(result.h1, references[0]),
            relative_error(result.h2, references[1]),
        ]
    return Comparison(
        contacts_first=result.contacts_first[BALLS],
        contacts_first_truth=int(contacts_first),
        rel_err_h1=errors[0],
        rel_err_h2=errors[1],
        cond_h1=float(cond[0]),
        cond_h2=float(cond[1]),
    )


def reference_text(value) -> str:
    """A reference height as stored in the accuracy tables: REFERENCE_DIGITS digits ("" for a
    bounce the reference does not have)."""
    import mpmath

    return "" if value is None else mpmath.nstr(value, REFERENCE_DIGITS)


def within_rule(row: Comparison) -> bool:
    """The rule: contact counts equal; each error <= TOLERANCE and <= CONDITIONING_FACTOR x
    conditioning."""
    if row.contacts_first != row.contacts_first_truth:
        return False
    return all(
        error <= min(TOLERANCE, CONDITIONING_FACTOR * cond)
        for error, cond in ((row.rel_err_h1, row.cond_h1), (row.rel_err_h2, row.cond_h2))
    )
