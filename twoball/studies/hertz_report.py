"""The paper's three statistics with the Hertz force, beside the linear ones (``twoball report``).

The paper's question: does the delayed rebound survive a realistic contact, and where? The rows
are counted on the shipped two-ball Hertz cubes (``hertz-h1e2``, ``hertz-h1e4``: the paper's
50 x 50 x 50 linear grid, one cube per drop height, since the Hertz force is not scale-free;
twoball/batch/hertz_sweep.py) exactly as :func:`twoball.studies.report.sweep_rows` counts the linear
``paper`` cube: a delayed rebound is h2 > h1 (False where h2 does not exist), "below the ICM" is
h1 / h_ICM < 1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from twoball.studies.rows import Row, _grid_words, _percent

HERTZ_CUBES = ("hertz-h1e2", "hertz-h1e4")  # the shipped ones, lowest drop first


@dataclass(frozen=True)
class Counts:
    """The paper's three statistics' counts on one cube."""

    cases: int
    delayed: int
    below: int
    both: int  # delayed and below the ICM
    missing: int  # no second apex


def counts(cube) -> Counts:
    """Count the cases of a cube (float32 stores: decided on the stored values, except
    delayed_rebound, which the sweep decided in float64)."""
    data = cube[["h2", "h1_over_icm", "delayed_rebound"]].load()
    delayed = data.delayed_rebound.values
    below = data.h1_over_icm.values < 1.0
    return Counts(
        cases=int(delayed.size),
        delayed=int(delayed.sum()),
        below=int(below.sum()),
        both=int((delayed & below).sum()),
        missing=int(np.isnan(data.h2.values).sum()),
    )


def where(cube) -> str:
    """Where a cube's delayed rebounds lie: the median (and 90 % quantile) of each axis over them
    (for eps the 10 % quantile, they lean to high eps), their share at each end of each axis,
    and the largest h2/h1 and where it is."""
    data = cube[["delayed_rebound", "h2_over_h1"]].load()
    delayed = data.delayed_rebound.values
    if not delayed.any():
        return "none"
    at_eps, at_mu, at_tau = np.nonzero(delayed)
    eps, mu, tau = (cube[d].values for d in ("eps", "mu", "tau_ratio"))
    q = {
        "mu": np.quantile(mu[at_mu], [0.5, 0.9]),
        "tau_ratio": np.quantile(tau[at_tau], [0.5, 0.9]),
        "eps": np.quantile(eps[at_eps], [0.5, 0.1]),
    }
    ends = {
        "eps": (delayed[0].mean(), delayed[-1].mean(), eps),
        "mu": (delayed[:, 0].mean(), delayed[:, -1].mean(), mu),
        "tau_ratio": (delayed[:, :, 0].mean(), delayed[:, :, -1].mean(), tau),
    }
    ratio = np.where(delayed, data.h2_over_h1.values, -np.inf)
    top = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
    shown = ", ".join(
        f"{d} {cube[d].values[i]:.3g}" for d, i in zip(cube.h1.dims, top, strict=True)
    )
    return (
        f"half at mu <= {q['mu'][0]:.3g} (90 % <= {q['mu'][1]:.3g}), half at tau_ratio <= "
        f"{q['tau_ratio'][0]:.3g} (90 % <= {q['tau_ratio'][1]:.3g}), half at eps >= "
        f"{q['eps'][0]:.3g} (90 % >= {q['eps'][1]:.3g}); share of the cases "
        + ", ".join(
            f"{100 * low:.1f} % at {d} = {v[0]:.3g} and {100 * high:.1f} % at {v[-1]:.3g}"
            for d, (low, high, v) in ends.items()
        )
        + f"; largest h2/h1 {ratio[top]:.3g} at {shown}"
    )


def hertz_rows(cube, linear=None) -> list[Row]:
    """The paper's three statistics (and where the delayed rebounds are) on a Hertz cube; with
    ``linear`` (the paper cube) the linear numbers are quoted beside them."""
    found = counts(cube)
    grid = _grid_words(cube) + " (Hertz units)"
    label = f"Hertz force, H = {cube.attrs['height']:g}"
    base = None if linear is None else counts(linear)

    def beside(part: str, whole: str) -> str:
        if base is None:
            return ""
        shown = _percent(getattr(base, part), getattr(base, whole))
        return f"; linear force (paper cube, H = {linear.attrs['height']:g}): {shown}"

    return [
        Row(
            f"{label}: share of the grid with a delayed rebound",
            "12.3 % (linear)",
            _percent(found.delayed, found.cases),
            f"{grid}; {found.missing} cases with no second apex count as not delayed"
            + beside("delayed", "cases"),
        ),
        Row(
            f"{label}: of those, share with h1 below the ICM",
            "93 % (linear)",
            _percent(found.both, found.delayed),
            "same grid" + beside("both", "delayed"),
        ),
        Row(
            f"{label}: of cases with h1 below the ICM, share with a delayed rebound",
            "22 % (linear)",
            _percent(found.both, found.below),
            "same grid" + beside("both", "below"),
        ),
        Row(
            f"{label}: where the delayed rebounds are",
            "(not studied)",
            where(cube),
            "over the cases with h2 > h1"
            + ("" if linear is None else f"; linear force (paper cube): {where(linear)}"),
        ),
    ]
