"""Scales and labels of the two unit systems results are shown in (the physics: twoball.presets)."""

from __future__ import annotations

from dataclasses import dataclass

from twoball import presets


@dataclass(frozen=True)
class Units:
    """Multiply a dimensionless height, time or force by these to show it."""

    length: float
    time: float
    force: float
    length_label: str
    time_label: str
    force_label: str

    def height(self, value: float) -> str:
        """A height as text with its unit, without an exponent where it is a plain number
        (211,950 rather than 2.1195e+05: read from the back of a classroom); in metres to
        three significant digits (8.84 m: a centimetre on a drop from 1 m)."""
        if self.length == 1.0:
            return number_text(value)
        return f"{value * self.length:.3g} m"


def number_text(value: float) -> str:
    """A number as text: grouped digits from 1e3 to 1e13 (9,256 beside 10,004, not 9256),
    five significant digits otherwise."""
    if 1e3 <= abs(value) < 1e13:
        return f"{value:,.0f}"
    return f"{value:.5g}"


DIMENSIONLESS = Units(1.0, 1.0, 1.0, "height X", "time tau", "force f")
SI = Units(
    presets.length_scale(),
    presets.time_scale(),
    presets.force_scale(),
    "height [m]",
    "time [s]",
    "force [N]",
)


def units_named(name: str) -> Units:
    return SI if name == "SI" else DIMENSIONLESS
