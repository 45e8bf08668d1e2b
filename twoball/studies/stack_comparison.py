"""A stack solver against stored reference values on one seeded drop: the one row type and the
one rule of the two stack accuracy tables (docs/accuracy.md, "The linear stack" and "The Hertz
stack"), whose references (:mod:`twoball.studies.stack_truth`,
:mod:`twoball.studies.hertz_truth`) share no code with each other or with the solvers."""

from __future__ import annotations

from dataclasses import dataclass

import mpmath

from twoball.studies.conditioning import CONDITIONING_FACTOR  # the two-ball rule's, as here


@dataclass(frozen=True)
class StackComparison:
    """The solver's contacts before h1 and the reference's (counts by contact, floor first,
    space-separated as the tables write them), the relative errors in h1 and h2 and the
    drop's conditioning of each (measured as docs/accuracy.md says)."""

    contacts_first: str
    contacts_first_truth: str
    rel_err_h1: float
    rel_err_h2: float
    cond_h1: float
    cond_h2: float

    def within(self, floor: float = 0.0) -> bool:
        """The tables' rule: equal contact counts, and h1 and h2 each within
        :data:`CONDITIONING_FACTOR` times its conditioning, or within ``floor`` if that is
        larger (the Hertz table's 1e-10)."""
        if self.contacts_first != self.contacts_first_truth:
            return False
        return all(
            error <= max(floor, CONDITIONING_FACTOR * cond)
            for error, cond in ((self.rel_err_h1, self.cond_h1), (self.rel_err_h2, self.cond_h2))
        )


def stack_against(
    case: dict,
    stored: dict,
    conditioning: tuple[float, float],
    force: str = "linear",
    method: str | None = None,
) -> StackComparison:
    """``simulate_stack`` on ``case`` (``force``, and ``method`` if given) against the stored
    reference heights and contact counts (``stored``: h1_truth, h2_truth as text,
    contacts_first_truth), with the drop's ``conditioning`` (cond_h1, cond_h2)."""
    from twoball.stacks import simulate_stack

    options = {"force": force} if method is None else {"force": force, "method": method}
    result = simulate_stack(
        case["mass_ratios"], case["eps"], case["tau_ratios"], height=case["height"], **options
    )
    with mpmath.workdps(40):
        h1_error, h2_error = (
            float(abs((mpmath.mpf(h) - mpmath.mpf(stored[f"{name}_truth"])) / mpmath.mpf(h)))
            for name, h in (("h1", result.h1), ("h2", result.h2))
        )
    return StackComparison(
        contacts_first=" ".join(str(count) for count in result.contacts_first),
        contacts_first_truth=stored["contacts_first_truth"],
        rel_err_h1=h1_error,
        rel_err_h2=h2_error,
        cond_h1=float(conditioning[0]),
        cond_h2=float(conditioning[1]),
    )
