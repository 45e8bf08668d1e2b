"""Parameters, restitution and damping, initial condition, ICM (docs/model.md)."""

import math

import numpy as np
import pytest
from cases import RESTITUTION

from twoball.model import (
    check_parameters,
    damping_ratios,
    decay_ratio,
    floor_contact_time,
    icm_height,
    initial_gap_height,
    restitution,
)


@pytest.mark.parametrize(
    "eps", [1e-6, 0.02, 0.1, math.exp(-2) * 0.999, math.exp(-2), 0.2, 0.5, 0.816, 0.999999, 1.0]
)
def test_restitution_round_trip_from_eps(eps):
    assert restitution(decay_ratio(eps)) == pytest.approx(eps, rel=1e-12, abs=0)


@pytest.mark.parametrize("r", [0.0, 1e-6, 0.3, 0.9, 0.999999, 1.0, 1.000001, 1.5, 3.0, 20.0])
def test_restitution_round_trip_from_r(r):
    # both branches and r = 1 exactly; the inverse is well conditioned in log eps
    assert decay_ratio(restitution(r)) == pytest.approx(r, rel=1e-9, abs=1e-12)


def test_critical_damping_is_exp_minus_two_and_branches_join():
    assert decay_ratio(math.exp(-2)) == pytest.approx(1.0, rel=1e-12)
    assert restitution(1.0 - 1e-9) == pytest.approx(math.exp(-2), rel=1e-7)
    assert restitution(1.0 + 1e-9) == pytest.approx(math.exp(-2), rel=1e-7)
    assert floor_contact_time(1.0 - 1e-9) == pytest.approx(2.0, rel=1e-6)
    assert floor_contact_time(1.0 + 1e-9) == pytest.approx(2.0, rel=1e-6)


def test_restitution_is_monotone():
    values = [restitution(r) for r in np.linspace(0.0, 5.0, 501)]
    assert all(b < a for a, b in zip(values, values[1:], strict=False))


def test_check_values_of_model_md():
    assert decay_ratio(0.816) == pytest.approx(RESTITUTION[0.816][0], abs=1e-12)
    assert floor_contact_time(decay_ratio(0.816)) == pytest.approx(RESTITUTION[0.816][1], abs=1e-10)
    assert decay_ratio(0.5) == pytest.approx(RESTITUTION[0.5][0], abs=1e-12)
    assert floor_contact_time(decay_ratio(0.5)) == pytest.approx(RESTITUTION[0.5][1], abs=1e-10)


def test_floor_contact_time_matches_the_damped_oscillator():
    # independent: integrate u'' + 2 r u' + u = 0 from u = 0, u' = -1 until the force
    # -(u + 2 r u') returns to zero, with a fine explicit midpoint scheme
    for r in (0.1, 0.6):
        dt = 1e-5
        u, v, t = 0.0, -1.0, 0.0
        while True:
            a = -u - 2 * r * v
            um, vm = u + 0.5 * dt * v, v + 0.5 * dt * a
            u, v = u + dt * vm, v + dt * (-um - 2 * r * vm)
            t += dt
            if t > 0.1 and u + 2 * r * v >= 0:
                break
        assert t == pytest.approx(floor_contact_time(r), abs=2e-5)
        assert v == pytest.approx(restitution(r), abs=1e-4)


def test_ball_damping_scales_with_the_reduced_mass():
    z01, z12 = damping_ratios(0.7, 0.7, 0.25)
    assert z12 == pytest.approx(z01 * math.sqrt(0.25 / 1.25), rel=1e-15)


def test_initial_condition_gives_the_delay():
    drop = check_parameters(0.816, 0.05, 0.3, height=1e4)
    fall_1 = math.sqrt(2 * drop.x1_0)
    fall_2 = math.sqrt(2 * drop.x2_0)
    assert fall_2 - fall_1 == pytest.approx(0.3 * drop.tau_f, rel=1e-12)
    assert initial_gap_height(1e4, 0.0) == 1e4


def test_icm_reduces_to_the_paper_formula_and_the_textbook_limit():
    height, gap = 1e4, 37.0
    for eps, mu in ((0.9, 0.01), (0.6, 0.3), (1.0, 0.2)):
        paper = (height * (eps**2 + 2 * eps - mu) ** 2 + gap * (1 + mu) * (mu - eps)) / (
            1 + mu
        ) ** 2
        assert icm_height(height, gap, eps, eps, mu) == pytest.approx(paper, rel=1e-12)
    # elastic, tiny upper ball, no gap: three times the speed, nine times the height
    assert icm_height(1.0, 0.0, 1.0, 1.0, 1e-12) == pytest.approx(9.0, rel=1e-10)


def test_icm_with_separate_restitutions_follows_the_collision_steps():
    # floor eps01 = 1, ball eps12 = 0 (perfectly inelastic): after the floor bounce both move
    # together with the momentum-weighted velocity; check against that closed form at dH = 0
    mu, height = 0.5, 2.0
    v = math.sqrt(2 * height)
    together = (v - mu * v) / (1 + mu)
    assert icm_height(height, 0.0, 1.0, 0.0, mu) == pytest.approx(together**2 / 2, rel=1e-12)


def _meeting_flight_by_flight(height, gap, eps01):
    """The balls' first meeting found flight by flight: the lower ball's bounces stepped one
    at a time, each flight searched by a root finder for the upper ball reaching it."""
    from scipy.optimize import brentq

    v_i = math.sqrt(2 * height)
    start, up = v_i, eps01 * v_i
    for _ in range(100_000):

        def apart(t, start=start, up=up):
            return height + gap - t * t / 2 - (up * (t - start) - (t - start) ** 2 / 2)

        end = start + 2 * up
        if apart(end) <= 0:
            t = brentq(apart, start, end, xtol=1e-13, rtol=1e-15)
            return t, up * (t - start) - (t - start) ** 2 / 2, up - (t - start)
        if up < 1e-12 * v_i:  # the bounces have died out: the lower ball rests on the floor
            break
        start, up = end, eps01 * up
    landing = math.sqrt(2 * (height + gap))
    return landing, 0.0, 0.0


@pytest.mark.parametrize(
    ("eps01", "gap"),
    [
        (0.9, 37.0),  # the textbook case: the first flight
        (0.9, 1.2e5),  # the second flight or later
        (0.9, 3e6),  # a gap of tau_ratio 1000 at H = 1e4: the balls meet late
        (1.0, 2e6),  # elastic: every flight alike, the meeting on the seventh or so
        (0.3, 1e6),  # the bounces die out first: the upper ball lands on the lower at rest
    ],
)
def test_icm_meets_on_the_flight_where_the_balls_really_meet(eps01, gap):
    """A gap too large for the lower ball's first flight: the meeting is on a later one (or on
    the ball at rest), found flight by flight; the first flight's formula put it below the
    floor and gave a negative h_ICM. Arrays give what each number gives."""
    from twoball.model import icm_meeting

    expected = _meeting_flight_by_flight(1e4, gap, eps01)
    found = icm_meeting(1e4, gap, eps01)
    assert found == pytest.approx(expected, rel=1e-9, abs=1e-9 * math.sqrt(2e4))
    assert found[1] >= 0.0
    assert icm_height(1e4, gap, eps01, eps01, 0.1) > 0.0
    gaps = np.array([37.0, gap])
    times, _, _ = icm_meeting(1e4, gaps, np.full(2, eps01))
    assert times[1] == pytest.approx(found[0], rel=1e-14)


@pytest.mark.parametrize(
    ("name", "value", "text"),
    [
        ("eps", 0.0, "eps must be a finite number in [0.01, 1]"),
        ("eps", 1.5, "eps must be a finite number in [0.01, 1]"),
        ("eps", float("nan"), "eps"),
        ("eps12", -0.1, "eps12 must be a finite number in [0.01, 1]"),
        ("mu", 0.0, "mu must be a finite number in [1e-09, 1e+06]"),
        ("mu", float("inf"), "mu must be a finite number in [1e-09, 1e+06]"),
        ("tau_ratio", -1e-9, "tau_ratio must be a finite number in [0, inf)"),
        ("tau_ratio", float("nan"), "tau_ratio"),
        ("height", 0.0, "height must be a finite number in (0, inf)"),
        ("height", float("-inf"), "height"),
        ("mu", "heavy", "mu must be a real number in [1e-09, 1e+06]"),
    ],
)
def test_bad_parameters_name_the_parameter_and_range(name, value, text):
    arguments = {"eps": 0.8, "mu": 0.1, "tau_ratio": 0.3, "eps12": None, "height": 1e4}
    arguments[name] = value
    with pytest.raises(ValueError) as error:
        check_parameters(
            arguments["eps"],
            arguments["mu"],
            arguments["tau_ratio"],
            eps12=arguments["eps12"],
            height=arguments["height"],
        )
    assert text in str(error.value)


def test_heights_read_without_an_exponent():
    from twoball.units import DIMENSIONLESS, SI, number_text

    assert number_text(211950.3) == "211,950" and number_text(9256.048) == "9,256"
    assert number_text(0.51234567) == "0.51235" and number_text(3e14) == "3e+14"
    assert DIMENSIONLESS.height(50076.39) == "50,076"
    # H = 1e4 is 1e4 m1 g / k = 1e4 * 0.6085 kg * 9.81 m/s^2 / 6e4 N/m = 0.99490 m
    assert SI.height(1e4) == "0.995 m"  # three significant digits


def test_icm_meeting_over_random_gaps_and_restitutions():
    """The flight found in closed form is the one stepped to, for 300 random gaps (up to 500
    times H) and floor restitutions (0.3 to 1): no flight off by one through rounding."""
    from twoball.model import icm_meeting

    rng = np.random.default_rng(7)
    gaps = 1e4 * 10 ** rng.uniform(-3, np.log10(500), 300)
    eps01 = np.where(rng.random(300) < 0.1, 1.0, rng.uniform(0.3, 1.0, 300))
    times, levels, speeds = icm_meeting(1e4, gaps, eps01)
    for i in range(300):
        expected = _meeting_flight_by_flight(1e4, gaps[i], eps01[i])
        found = (times[i], levels[i], speeds[i])
        assert found == pytest.approx(expected, rel=1e-8, abs=1e-8 * math.sqrt(2e4)), i


def test_icm_meeting_on_a_ball_at_rest_is_quiet():
    """A drop height of 1e-320: the lower ball lies on the floor, and the upper one meets it
    there after falling its gap, sqrt(2 dH); the flights' values, not taken, overflowed and the
    command line printed a RuntimeWarning (a researcher's trial)."""
    import warnings

    from twoball.model import icm_meeting

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert icm_meeting(1e-320, 0.1, 0.9) == (math.sqrt(0.2), 0.0, 0.0)
