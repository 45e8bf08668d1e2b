"""The presets in SI units (twoball/presets.py, docs/model.md "Presets: real balls in metres and
seconds"): the documented table is what the code computes, and the dashpots give the documented
restitutions when a mass on a spring and dashpot is integrated on its own."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest
from scipy.integrate import solve_ivp

from twoball import presets

MODEL_MD = Path(__file__).resolve().parents[1] / "docs" / "model.md"


def _documented_rows() -> dict[str, list[str]]:
    section = MODEL_MD.read_text().split("## Presets: real balls in metres and seconds")[1]
    rows = [line for line in section.splitlines() if line.startswith("| ") and " g |" in line]
    return {
        cells[0]: cells[1:]
        for cells in ([c.strip() for c in r.strip("|").split("|")] for r in rows)
    }


def _rebound_ratio(mass: float, stiffness: float, damping: float) -> float:
    """Exit over entry speed of a mass hitting a spring and dashpot that never pulls: the
    contact ends when the force k x + c x' reaches zero (x < 0 compressed)."""

    def motion(_, y):
        return [y[1], -(stiffness * y[0] + damping * y[1]) / mass]

    def released(_, y):
        return stiffness * y[0] + damping * y[1] if _ > 0 else -1.0

    released.terminal, released.direction = True, 1
    entry = -1.0
    period = 2 * math.pi * math.sqrt(mass / stiffness)
    run = solve_ivp(
        motion, (0, 2 * period), [0.0, entry], events=released, rtol=1e-11, atol=1e-14,
        method="DOP853",
    )  # fmt: skip
    return run.y_events[0][0][1] / -entry


@pytest.mark.parametrize("key", list(presets.PRESETS))
def test_the_documented_table_is_what_the_code_computes(key):
    preset = presets.PRESETS[key]
    pair = presets.ball_pair(preset)
    row = _documented_rows()[preset.label]
    shown = [
        f"{pair.m1 * 1e3:.1f} g", f"{pair.m2 * 1e3:.1f} g", f"{preset.mu:.4g}",
        f"{pair.stiffness:.3g} N/m", f"{preset.eps:.3f}", f"{preset.eps12:.3f}",
        f"{pair.damping_floor:.2f} N s/m", f"{pair.damping_balls:.3f} N s/m",
        f"{pair.floor_contact_ms:.2f} ms", f"{pair.drop_height:.0f}",
    ]  # fmt: skip
    assert row == shown


@pytest.mark.parametrize("key", list(presets.PRESETS))
def test_the_dashpots_give_the_restitutions(key):
    """Floor: the basketball on k and c01. Balls: their relative motion, with the reduced
    mass, on k and c12. Each rebounds with the preset's eps."""
    preset = presets.PRESETS[key]
    pair = presets.ball_pair(preset)
    reduced = pair.m1 * pair.m2 / (pair.m1 + pair.m2)
    floor = _rebound_ratio(pair.m1, pair.stiffness, pair.damping_floor)
    balls = _rebound_ratio(reduced, pair.stiffness, pair.damping_balls)
    assert floor == pytest.approx(preset.eps, rel=1e-7)
    assert balls == pytest.approx(preset.eps12, rel=1e-7)


def test_a_metre_is_the_documented_drop_height():
    assert re.search(r"basketball\s+dropped\s+from 1 m is of order 1e4", MODEL_MD.read_text())
    assert presets.metres_from_height(presets.ball_pair(presets.PRESETS["tennis"]).drop_height) == (
        pytest.approx(1.0, rel=1e-12)
    )
