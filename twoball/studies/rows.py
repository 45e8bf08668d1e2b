"""The rows of ``twoball report``'s table and how their numbers are worded, shared by the linear
rows (:mod:`twoball.studies.report`) and the Hertz ones (:mod:`twoball.studies.hertz_report`)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Row:
    """One claim of the paper: its number, ours, and what differs between the two."""

    claim: str
    paper: str
    ours: str
    note: str


def _percent(part: int, whole: int) -> str:
    return f"{100.0 * part / whole:.1f} % ({part} of {whole})" if whole else "no cases"


def _grid_words(cube) -> str:
    spacing = {cube[d].attrs.get("spacing", "?") for d in ("eps", "mu", "tau_ratio")}
    sizes = " x ".join(str(cube.sizes[d]) for d in ("eps", "mu", "tau_ratio"))
    return f"{sizes} {'/'.join(sorted(spacing))} grid at H = {cube.attrs['height']:g}"
