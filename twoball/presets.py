"""Presets a class knows, and the conversion between dimensionless and SI units.

The scales follow from the dimensionless variables of docs/model.md, "Bodies, coordinates,
forces".

Plain physics, no UI. Both presets drop a small ball on a size-7 basketball, so the lower ball,
and with it the unit conversion, is the same for both:

    z = X m1 g / k,   t = tau sqrt(m1 / k),   F = f m1 g,   H = h k / (m1 g).

Sources (restitution from a drop test as eps = sqrt(rebound / drop), mid-points of the ranges
the rules allow):

- Basketball: FIBA Official Basketball Rules, "Basketball Equipment" (size 7 ball): mass
  567-650 g; dropped from 1800 mm (bottom of the ball) it must rebound to 1200-1400 mm.
  m1 = 0.6085 kg, eps = sqrt(1300/1800) = 0.850.
- Tennis ball: ITF Rules of Tennis, Appendix I: mass 56.0-59.4 g; dropped from 100 in (254 cm)
  onto concrete it must rebound 53-58 in (135-147 cm). m2 = 0.0577 kg, eps12 = sqrt(55.5/100)
  = 0.745 (the ball-ball restitution is taken as the small ball's own, an approximation).
- Table-tennis ball: ITTF Handbook, Laws of Table Tennis 2.3 (40 mm, 2.7 g) and ITTF Technical
  Leaflet T3 (dropped from 305 mm onto a steel block it bounces 240-260 mm): m2 = 0.0027 kg,
  eps12 = sqrt(250/305) = 0.905.
- Stiffness: the model has one linear stiffness k for both contacts. k = 6.0e4 N/m is an order
  of magnitude, not a measurement of these balls: it is the value for which a basketball dropped
  from 1 m has H ~ 1e4 (docs/model.md, "Initial condition") and it gives a floor contact of
  about 10 ms (tau_f sqrt(m1/k)), the duration measured for inflated balls on a rigid floor
  (R. Cross, "The bounce of a ball", Am. J. Phys. 67, 222 (1999)). Change STIFFNESS to use a
  measured value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from twoball.model import damping_ratios, floor_contact_time

GRAVITY = 9.81  # m/s^2
BASKETBALL_MASS = 0.6085  # kg, FIBA mid-range
STIFFNESS = 6.0e4  # N/m, order of magnitude (see the module docstring)
DEFAULT_DROP_METRES = 1.0


@dataclass(frozen=True)
class Preset:
    """One classroom drop: the model's parameters and where each number comes from."""

    label: str
    eps: float
    eps12: float
    mu: float
    tau_ratio: float
    source: str


def restitution_from_drop(drop: float, rebound: float) -> float:
    """eps = sqrt(rebound / drop): the speed ratio of a bounce from the heights of a drop test."""
    return math.sqrt(rebound / drop)


BASKETBALL_EPS = restitution_from_drop(1800.0, 1300.0)

PRESETS = {
    "tennis": Preset(
        label="Tennis ball on a basketball",
        eps=BASKETBALL_EPS,
        eps12=restitution_from_drop(100.0, 55.5),
        mu=0.0577 / BASKETBALL_MASS,
        tau_ratio=0.01,
        source="FIBA (basketball 567-650 g, rebound 1200-1400 mm from 1800 mm), "
        "ITF Rules of Tennis App. I (56.0-59.4 g, rebound 53-58 in from 100 in); "
        "balls held nearly touching (tau_d/tau_f = 0.01).",
    ),
    "ping-pong": Preset(
        label="Ping-pong ball on a basketball",
        eps=BASKETBALL_EPS,
        eps12=restitution_from_drop(305.0, 250.0),
        mu=0.0027 / BASKETBALL_MASS,
        tau_ratio=0.01,
        source="FIBA (basketball), ITTF Laws 2.3 and Technical Leaflet T3 (2.7 g, bounce "
        "240-260 mm from 305 mm); balls held nearly touching (tau_d/tau_f = 0.01).",
    ),
}


def length_scale(mass: float = BASKETBALL_MASS, stiffness: float = STIFFNESS) -> float:
    """Metres per unit of dimensionless height: m1 g / k."""
    return mass * GRAVITY / stiffness


def time_scale(mass: float = BASKETBALL_MASS, stiffness: float = STIFFNESS) -> float:
    """Seconds per unit of dimensionless time: sqrt(m1 / k)."""
    return math.sqrt(mass / stiffness)


def force_scale(mass: float = BASKETBALL_MASS) -> float:
    """Newtons per unit of dimensionless force: m1 g."""
    return mass * GRAVITY


def height_from_metres(metres: float) -> float:
    """Dimensionless drop height H = h k / (m1 g) of a drop from ``metres``."""
    return metres / length_scale()


def metres_from_height(height: float) -> float:
    """The drop height in metres of a dimensionless H."""
    return height * length_scale()


@dataclass(frozen=True)
class BallPair:
    """A preset in SI units: the bodies and contacts behind its dimensionless parameters."""

    m1: float  # kg, the basketball
    m2: float  # kg, the ball on top
    stiffness: float  # N/m, both contacts
    damping_floor: float  # N s/m, c01
    damping_balls: float  # N s/m, c12
    floor_contact_ms: float  # one floor contact of the basketball
    drop_height: float  # dimensionless H of a drop from DEFAULT_DROP_METRES


def ball_pair(preset: Preset) -> BallPair:
    """The masses, stiffness and dashpots of ``preset`` (docs/model.md, "Bodies, coordinates,
    forces" and "Restitution and damping"): the contact force is k eta + c eta' in newtons,
    f = eta + 2 zeta eta' in units of m1 g, so c = 2 zeta sqrt(k m1) for either contact."""
    zeta01, zeta12 = damping_ratios(preset.eps, preset.eps12, preset.mu)
    scale = 2.0 * math.sqrt(STIFFNESS * BASKETBALL_MASS)
    return BallPair(
        m1=BASKETBALL_MASS,
        m2=preset.mu * BASKETBALL_MASS,
        stiffness=STIFFNESS,
        damping_floor=scale * zeta01,
        damping_balls=scale * zeta12,
        floor_contact_ms=1e3 * floor_contact_time(zeta01) * time_scale(),
        drop_height=height_from_metres(DEFAULT_DROP_METRES),
    )
