"""The check values of docs/model.md, once: every test that compares with them imports them here.

They are printed in the specification to the digits given here, independently of the package.
"""

from typing import NamedTuple


class Case(NamedTuple):
    """A drop at H = 1e4 (eps01 = eps12 = eps) and its apex heights from docs/model.md."""

    eps: float
    mu: float
    tau_ratio: float
    h1: float
    h2: float

    @property
    def drop(self) -> tuple[float, float, float]:
        """(eps, mu, tau_ratio), the positional arguments of ``twoball.simulate``."""
        return self.eps, self.mu, self.tau_ratio


# docs/model.md, "What is measured": the paper's close-up (four ball contacts in the first
# bounce, all while the lower ball is on the floor; a delayed rebound) and a benign case.
CLOSE_UP = Case(0.9, 0.01, 0.01, h1=9256.04845, h2=50076.3922)
CLOSE_UP_CONTACTS = 4
BENIGN = Case(0.816, 0.05, 0.3, h1=26344.4166, h2=19354.2754)

# docs/model.md, "Restitution and damping": eps -> (r = zeta01, tau_f).
RESTITUTION = {0.816: (0.0674788868542, 3.01340068720), 0.5: (0.255275637649, 2.71528919463)}
