"""The paper's three statistics with the Hertz force, beside the linear ones (``twoball report``).

The paper's question: does the delayed rebound survive a realistic contact, and where? The rows
are counted on the shipped two-ball Hertz cubes (``hertz-h1e2``, ``hertz-h1e4``: the paper's
50 x 50 x 50 linear grid, one cube per drop height, since the Hertz force is not scale-free;
twoball/hertz_sweep.py) exactly as :func:`twoball.studies.report.sweep_rows` counts the linear
``paper`` cube: a delayed rebound is h2 > h1 (False where h2 does not exist), "below the ICM" is
h1 / h_ICM < 1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from twoball.studies.report import Row, _grid_words, _percent

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
    """Where a cube's delayed rebounds lie: the range of each axis they span, the largest
    h2/h1 and where it is, and their share at the smallest and the largest mu."""
    data = cube[["delayed_rebound", "h2_over_h1"]].load()
    delayed = data.delayed_rebound.values
    if not delayed.any():
        return "none"
    spans = []
    for axis, dim in enumerate(("eps", "mu", "tau_ratio")):
        values = cube[dim].values[np.any(delayed, axis=tuple(k for k in range(3) if k != axis))]
        spans.append(f"{dim} {values.min():.3g} to {values.max():.3g}")
    ratio = np.where(delayed, data.h2_over_h1.values, -np.inf)
    at = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
    top = ", ".join(f"{d} {cube[d].values[i]:.3g}" for d, i in zip(cube.h1.dims, at, strict=True))
    light, heavy = delayed[:, 0, :].mean(), delayed[:, -1, :].mean()
    mu = cube.mu.values
    return (
        f"{'; '.join(spans)}; largest h2/h1 {ratio[at]:.3g} at {top}; share "
        f"{100 * light:.1f} % at mu = {mu[0]:.3g}, {100 * heavy:.1f} % at mu = {mu[-1]:.3g}"
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
            "ranges spanned by the cases with h2 > h1",
        ),
    ]
