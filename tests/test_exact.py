"""The exact solver against closed forms, conservation laws, the check values of docs/model.md and
scipy."""

import math
import subprocess
import sys

import numpy as np
import pytest
from cases import BENIGN, CLOSE_UP
from scipy.integrate import solve_ivp
from scipy.optimize import minimize_scalar

import twoball
from twoball.kernels import codes, phases
from twoball.model import damping_ratios, decay_ratio, restitution
from twoball.observables import BALLS, FLOOR


def _advance(kind, state, mu, z01, z12, horizon=np.inf):
    """One phase from the absolute state (x1, x2, v1, v2); returns (event, tau, x1, x2, v1, v2).
    The kernel carries (x1, eta, v1, eta') with eta = x2 - x1 (phases.state_at)."""
    x1, x2, v1, v2 = state
    prepared = phases.prepare(mu, z01, z12)
    event, tau, y1, eta, w1, deta, _, _ = phases.advance_phase(
        kind, 0.0, x1, x2 - x1, v1, v2 - v1, horizon, codes.EVENT_TIME, prepared
    )
    return event, tau, y1, y1 + eta, w1, w1 + deta


@pytest.mark.parametrize("mu", [1e-5, 1e-3, 0.1, 1.0, 10.0, 1e3])
@pytest.mark.parametrize("eps", [0.05, math.exp(-2), 0.5, 0.9, 1.0])
def test_isolated_ball_contact_returns_eps(mu, eps):
    # Both balls in the air: gravity drops out of the relative motion exactly, so the
    # separation speed over the approach speed must be eps(r) of docs/model.md, "Restitution and
    # damping".
    z01, z12 = damping_ratios(eps, eps, mu)
    approach = 100.0
    event, tau, *touching = _advance(
        phases.FREE, (1e3, 1e3 + approach, 0.0, -approach), mu, z01, z12
    )
    assert event == codes.EVENT_BALL and tau == pytest.approx(1.0, rel=1e-14)
    event, tau, x1, x2, v1, v2 = _advance(phases.BALL, touching, mu, z01, z12)
    assert event == codes.EVENT_BALL
    assert (v2 - v1) / approach == pytest.approx(eps, rel=1e-9)
    # momentum of the pair changes by gravity only: (v1 + mu v2) drops by (1 + mu) tau
    before = touching[2] + mu * touching[3]
    assert v1 + mu * v2 == pytest.approx(before - (1 + mu) * tau, rel=1e-12)


@pytest.mark.parametrize("eps", [0.02, math.exp(-2), 0.3, 0.816, 0.999999, 1.0])
def test_isolated_floor_contact_returns_eps(eps):
    # An impact speed of 1e11 makes gravity's share of the contact (~pi/1e11) negligible.
    z01, z12 = damping_ratios(eps, eps, 0.1)
    speed = 1e11
    state = (0.0, 1e13, -speed, 0.0)  # the upper ball far above, out of the way
    event, tau, x1, x2, v1, v2 = _advance(phases.FLOOR, state, 0.1, z01, z12)
    assert event == codes.EVENT_FLOOR
    assert v1 / speed == pytest.approx(eps, rel=1e-9)
    r = decay_ratio(eps)
    assert restitution(r) == pytest.approx(eps, rel=1e-12)


def _energy(trajectory, mu):
    """Kinetic + gravitational + spring energy; with the spring counted wherever the bodies
    overlap, this is non-increasing along the clamped model (docs/model.md, "Bodies, coordinates,
    forces")."""
    x1, x2, v1, v2 = trajectory.x1, trajectory.x2, trajectory.v1, trajectory.v2
    overlap = np.minimum(x2 - x1, 0.0)
    floor = np.minimum(x1, 0.0)
    return 0.5 * v1**2 + 0.5 * mu * v2**2 + x1 + mu * x2 + 0.5 * floor**2 + 0.5 * overlap**2


CASES = [
    (0.9, 0.01, 0.01, 1e4),
    (0.816, 0.05, 0.3, 1e4),
    (0.5, 1e-4, 0.05, 1e3),
    (0.02, 0.3, 0.0, 1e2),
    (math.exp(-2), 1e-3, 0.2, 1e4),
    (1.0, 0.2, 2.0, 1e3),
    (0.7, 50.0, 0.5, 1e2),
]


@pytest.mark.parametrize(("eps", "mu", "tau_ratio", "height"), CASES)
def test_energy_never_increases(eps, mu, tau_ratio, height):
    result = twoball.simulate(eps, mu, tau_ratio, height=height, dense_output=True)
    energy = _energy(result.trajectory, mu)
    scale = height + mu * result.x2_0
    assert np.max(np.diff(energy)) <= 1e-12 * scale
    if eps == 1.0:  # no damping anywhere: energy is conserved
        assert np.ptp(energy) <= 1e-11 * scale


@pytest.mark.parametrize(("eps", "mu", "tau_ratio", "height"), CASES)
def test_balls_never_pass_through_each_other(eps, mu, tau_ratio, height):
    # Energy bounds the overlap: 1/2 min(eta, 0)^2 <= E0 - x1 - mu x2 at every instant.
    result = twoball.simulate(eps, mu, tau_ratio, height=height, dense_output=True)
    tr = result.trajectory
    energy0 = height + mu * result.x2_0
    allowed = np.sqrt(2.0 * np.maximum(energy0 - tr.x1 - mu * tr.x2, 0.0))
    assert np.all(tr.x2 - tr.x1 >= -allowed - 1e-9 * energy0)
    # and at each apex the upper ball is above the lower one's surface
    apex_rows = np.searchsorted(tr.t, result.apex_t)
    assert np.all(tr.x2[apex_rows] > tr.x1[apex_rows] - 1e-9 * energy0)


def test_close_up_case_of_model_md():
    result = twoball.simulate(0.9, 0.01, 0.01)
    assert result.h1 == pytest.approx(CLOSE_UP.h1, rel=1e-8)
    assert result.h2 == pytest.approx(CLOSE_UP.h2, rel=1e-8)
    assert result.contacts_first == [1, 4]  # one floor contact, four ball contacts
    assert result.delayed_rebound
    floor = [c for c in result.contacts if c.contact == FLOOR][0]
    ball = [c for c in result.contacts if c.contact == BALLS and c.start < result.t1]
    assert len(ball) == 4
    assert all(floor.start <= c.start and c.end <= floor.end for c in ball)


def test_second_check_value_of_model_md():
    result = twoball.simulate(0.816, 0.05, 0.3)
    assert result.h1 == pytest.approx(BENIGN.h1, rel=1e-8)
    assert result.h2 == pytest.approx(BENIGN.h2, rel=1e-8)


@pytest.mark.parametrize(
    ("height", "h2_over_h1", "h1_over_icm"),
    [
        (1e2, (1.399, 1e-3), (0.567, 1e-3)),
        (1e3, (0.868, 1e-3), (0.574, 1e-3)),
        (1e4, (0.7347, 1e-4), (0.5760, 1e-4)),
        (1e5, (0.695, 1e-3), (0.5765, 1e-4)),
        (1e6, (0.683, 1e-3), (0.5766, 1e-4)),
    ],
)
def test_height_table_of_model_md(height, h2_over_h1, h1_over_icm):
    result = twoball.simulate(0.816, 0.05, 0.3, height=height)
    assert result.h2_over_h1 == pytest.approx(h2_over_h1[0], abs=h2_over_h1[1] / 2)
    assert result.h1_over_icm == pytest.approx(h1_over_icm[0], abs=h1_over_icm[1] / 2)


@pytest.mark.parametrize(
    ("eps", "mu", "tau_ratio"), [(0.816, 0.05, 0.3), (0.7, 0.2, 0.8), (0.95, 0.1, 1.5)]
)
def test_exact_agrees_with_dop853_at_tight_tolerance(eps, mu, tau_ratio):
    exact_result = twoball.simulate(eps, mu, tau_ratio, height=1e3)
    reference = twoball.simulate(
        eps, mu, tau_ratio, height=1e3, method="DOP853", rtol=1e-12, atol=1e-12
    )
    assert reference.reason is None
    for name in ("h1", "h2", "t1", "t2"):
        assert getattr(exact_result, name) == pytest.approx(getattr(reference, name), rel=1e-8)
    assert exact_result.contacts_first == reference.contacts_first


def _grazing_state(depth):
    """A floor-contact state whose upper ball, overlapping but separating, comes back to touch
    the lower one with a ball force that reaches at most ``depth`` (negative: no touch).

    The touch is found on an independent DOP853 solution (rtol 1e-13) of the smooth floor-phase
    equations: g12 has a local minimum at t*, and the upper ball is shifted so that g12(t*) is
    exactly -depth there.
    """
    mu = 1.0
    z01, z12 = damping_ratios(0.9, 0.2, mu)

    def rhs(t, y):
        return [y[2], y[3], -1.0 - (y[0] + 2 * z01 * y[2]), -1.0]

    start = np.array([-3.0, 0.0, 0.0, 4.0])
    sol = solve_ivp(rhs, (0, 3), start, method="DOP853", rtol=1e-13, atol=1e-13, dense_output=True)

    def g12(t):
        x1, x2, v1, v2 = sol.sol(t)
        return (x2 - x1) + 2 * z12 * (v2 - v1)

    touch = minimize_scalar(g12, bounds=(1.7, 2.1), method="bounded", options={"xatol": 1e-12})
    start[1] += -touch.fun - depth
    return start, mu, z01, z12, touch.x


@pytest.mark.parametrize("depth", [1e-6, 1e-10])
def test_grazing_touch_is_found(depth):
    state, mu, z01, z12, touch_time = _grazing_state(depth)
    assert state[1] - state[0] < 0  # overlapping at the start, but the force is off: g > 0
    event, tau, *_ = _advance(phases.FLOOR, tuple(state), mu, z01, z12)
    assert event == codes.EVENT_BALL
    assert tau == pytest.approx(touch_time, abs=10 * math.sqrt(depth))


@pytest.mark.parametrize("depth", [1e-6, 1e-10])
def test_near_miss_is_not_a_contact(depth):
    state, mu, z01, z12, touch_time = _grazing_state(-depth)
    event, tau, *_ = _advance(phases.FLOOR, tuple(state), mu, z01, z12)
    assert event == codes.EVENT_FLOOR  # the floor contact ends first, the balls never push
    assert tau > touch_time


def test_dense_trajectory_matches_the_apexes_and_forces():
    result = twoball.simulate(0.816, 0.05, 0.3, dense_output=True)
    tr = result.trajectory
    # the sampled heights reach, and never exceed, the reported first apex in its flight
    near = (tr.t > result.t1 - 5) & (tr.t < result.t1 + 5)
    assert tr.x2[near].max() <= result.h1 + 1e-9 * result.h1
    assert tr.x2[near].max() == pytest.approx(result.h1, rel=1e-6)
    # forces push only inside the reported contact intervals
    inside = np.zeros_like(tr.t, dtype=bool)
    for c in result.contacts:
        if c.contact == BALLS:
            inside |= (tr.t >= c.start) & (tr.t <= c.end)
    assert np.all(tr.f12[~inside] == 0.0)
    assert np.all(tr.f12 >= 0.0) and np.all(tr.f01 >= 0.0)


def test_upper_ball_coming_to_rest_is_a_stated_reason():
    result = twoball.simulate(0.02, 0.3, 0.0, height=1e2)
    assert result.h2 is None and result.t2 is None
    assert result.reason == "the upper ball came to rest on the lower one"
    assert math.isfinite(result.end_time)


def test_until_first_stops_at_the_first_apex_and_until_time_stops_there():
    first = twoball.simulate(0.816, 0.05, 0.3, until="first")
    assert first.h2 is None and first.end_time == first.t1
    later = twoball.simulate(0.816, 0.05, 0.3, until=1000.0)
    assert later.end_time == 1000.0
    assert later.h1 == pytest.approx(first.h1, rel=1e-14)
    assert len(later.apex_t) >= 2


def test_contacts_per_bounce_partition_the_contacts():
    result = twoball.simulate(0.9, 0.01, 0.01)
    counts = result.contacts_per_bounce(BALLS)
    assert counts[0] == result.contacts_first[BALLS]
    assert sum(counts) == sum(
        1 for c in result.contacts if c.contact == BALLS and c.start < result.t2
    )
    assert result.contacts_per_bounce(FLOOR)[0] == result.contacts_first[FLOOR]


@pytest.mark.parametrize(
    ("arguments", "text"),
    [
        ({"until": "third"}, "until must be 'first', 'second' or a time"),
        ({"until": -1.0}, "until"),
        ({"method": "Euler"}, "method must be one of"),
        ({"method": "DOP853", "rtol": 0.0}, "rtol must be a finite number in (0, 1)"),
        ({"rtol": 1e-6}, "rtol and atol apply to the scipy methods only"),
    ],
)
def test_bad_solver_arguments(arguments, text):
    with pytest.raises(ValueError, match=None) as error:
        twoball.simulate(0.8, 0.1, 0.3, **arguments)
    assert text in str(error.value)


def test_compiled_kernels_load_from_the_disk_cache_in_any_order():
    # numba's disk cache once broke the boxing of returned arrays in a fresh process when a
    # compiled caller of prepare() was loaded before prepare itself; run the public paths in a
    # new process, in the order a sweep after a simulate uses them.
    twoball.simulate(0.9, 0.01, 0.01, dense_output=True)  # make sure the cache is on disk
    script = (
        "import numpy as np, twoball\n"
        "from twoball.kernels import phases, runs\n"
        "twoball.simulate(0.9, 0.01, 0.01)\n"
        "prepared = phases.prepare(0.01, 0.05, 0.005)\n"
        "runs.run(1e4, 1e4, 2, np.inf, prepared, False, False)\n"
        "print(twoball.simulate(0.9, 0.01, 0.01, dense_output=True).h1)\n"
    )
    completed = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=300
    )
    assert completed.returncode == 0, completed.stderr
    assert float(completed.stdout) == pytest.approx(CLOSE_UP.h1, rel=1e-8)
