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
        """A height as text with its unit."""
        return f"{value * self.length:.5g}{'' if self.length == 1.0 else ' m'}"


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
