"""The N-ball stack (twoball.stacks) against independent computations: the two-ball solver, a
DOP853 reference, energy, and the ICM chain (docs/model.md, "Stacks of N balls")."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from cases import BENIGN, CLOSE_UP, CLOSE_UP_CONTACTS
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from stack_reference import reference_stack

import twoball
from twoball.errors import ParameterError, SolverError, Status
from twoball.kernels import stack as kernel
from twoball.stacks import check_stack, icm_chain, simulate_stack
from twoball.stacks.model import _apex_bound
from twoball.stacks.stack import METHODS, _store_for


def _energy(stack, trajectory) -> np.ndarray:
    """Kinetic + gravity + the springs of every overlapping contact: never rises (docs/model.md,
    "Stacks of N balls"; a clamped contact that overlaps stores no more than 1/2 eta^2, and its
    overlap shrinks while the force is clamped)."""
    masses = stack.masses
    heights, speeds = trajectory.x, trajectory.v
    eta = np.concatenate([heights[:, :1], np.diff(heights, axis=1)], axis=1)
    springs = 0.5 * np.where(eta < 0.0, eta, 0.0) ** 2
    return (
        0.5 * (masses * speeds**2).sum(axis=1)
        + (masses * heights).sum(axis=1)
        + springs.sum(axis=1)
    )


@pytest.mark.parametrize("case", [CLOSE_UP, BENIGN])
def test_two_balls_are_simulate(case):
    pair = simulate_stack([case.mu], case.eps, case.tau_ratio)
    assert pair.h1 == pytest.approx(case.h1, abs=1e-4)  # the digits printed in docs/model.md
    assert pair.h2 == pytest.approx(case.h2, abs=1e-4)
    single = twoball.simulate(*case.drop)
    assert abs(pair.h1 - single.h1) <= 1e-12 * single.h1
    assert abs(pair.h2 - single.h2) <= 1e-12 * single.h2
    if case is CLOSE_UP:
        assert pair.contacts_first[1] == CLOSE_UP_CONTACTS


def test_two_balls_are_simulate_on_a_sample():
    """20 seeded drops, eps 0.3-1 and eps12 apart, mu 1e-2 to 10, gaps 0 to 1.5."""
    rng = np.random.default_rng(7)
    for _ in range(20):
        eps, eps12 = rng.uniform(0.3, 1.0, 2)
        mu, tau_ratio = 10 ** rng.uniform(-2, 1), rng.uniform(0.0, 1.5)
        single = twoball.simulate(eps, mu, tau_ratio, eps12=eps12)
        pair = simulate_stack([mu], [eps, eps12], tau_ratio)
        assert pair.contacts_first == single.contacts_first
        theirs_all = list(zip(single.apex_t, single.apex_h, strict=True))
        for mine, theirs in zip(pair.apexes[-1], theirs_all, strict=True):
            assert abs(mine[1] - theirs[1]) <= 1e-12 * theirs[1], (eps, eps12, mu, tau_ratio)
            assert mine[0] == pytest.approx(theirs[0], rel=1e-12)


@pytest.mark.slow  # DOP853 with bounded steps: 5-10 s a drop
@pytest.mark.parametrize(
    "stack",
    [([0.2, 0.2], 0.9, 0.2), ([0.3, 0.1], [0.8, 0.7, 0.9], [0.5, 0.1])],
    ids=["paper-like", "three-eps"],
)
def test_three_balls_agree_with_dop853(stack):
    result = simulate_stack(*stack)
    made = result.stack
    heights, first = reference_stack(made.masses, made.zeta, made.x_start)
    assert first == result.contacts_first
    assert heights[0] == pytest.approx(result.h1, rel=1e-9)
    assert heights[1] == pytest.approx(result.h2, rel=1e-9)


@pytest.mark.parametrize("stack", [([0.2, 0.2], 0.9, 0.2), ([0.5] * 5, 0.7, 0.3)])
def test_energy_never_rises(stack):
    first = simulate_stack(*stack)
    times = np.unique(
        np.concatenate(
            [np.linspace(0.0, first.end_time, 4001)]
            + [np.linspace(c.start, c.end, 9) for c in first.contacts]
        )
    )
    result = simulate_stack(*stack, t_eval=times)
    energy = _energy(result.stack, result.trajectory)
    scale = energy[0]
    assert np.diff(energy).max() <= 1e-11 * scale
    assert energy[-1] < energy[0]  # damped contacts lose energy


def test_elastic_stack_conserves_energy_between_contacts():
    result = simulate_stack([0.2, 0.2], 1.0, 0.5, t_eval=np.linspace(0.0, 400.0, 2001))
    energy = _energy(result.stack, result.trajectory)
    assert np.ptp(energy) <= 1e-11 * energy[0]


def test_light_elastic_stack_approaches_the_icm_chain():
    """Tiny mass ratios, collisions far apart (big gaps, a drop high enough that they happen at
    the floor): the top ball of three goes up 49 times as high, less O(mass ratio)."""
    ratios = [1e-3, 1e-3]
    result = simulate_stack(ratios, 1.0, [2.0, 2.0], height=1e8, until="first")
    chain = icm_chain(result.stack)
    assert chain[-1] / result.stack.height == pytest.approx(49.0, rel=2e-2)
    firsts = [next(c for c in result.contacts if c.contact == i) for i in range(3)]
    assert firsts[0].end < firsts[1].start and firsts[1].end < firsts[2].start  # independent
    assert result.contacts_first[-1] == 1
    assert result.h1 == pytest.approx(chain[-1], rel=2e-3)


def test_the_apex_bound_is_the_two_ball_one():
    from twoball.model import apex_bound

    made = check_stack([0.3], 1.0, 0.5, height=24.0)
    drop = twoball.check_parameters(1.0, 0.3, 0.5, height=24.0)
    assert _apex_bound(made, "linear") == pytest.approx(apex_bound(drop), rel=1e-14)


def test_icm_chain_is_the_two_ball_icm():
    made = check_stack([0.05], 0.816, 0.0)
    assert icm_chain(made)[-1] == pytest.approx(twoball.simulate(0.816, 0.05, 0.0).h_icm, rel=1e-12)


@pytest.mark.parametrize(("eps", "mu", "tau_ratio"), [(0.9, 0.1, 10.0), (0.7, 0.5, 2.0)])
def test_a_two_ball_stack_s_icm_is_the_drop_s_with_its_gap(eps, mu, tau_ratio):
    """The chain takes the gaps: a two-ball stack's h_ICM is the two-ball drop's (its formula
    with dH), linear and Hertz (the Hertz cubes' formula with the Hertz release's gap). It had
    left the gap out: h1/h_ICM 0.948 against the drop's 1.016 at tau_ratio 10."""
    from twoball.model import icm_height

    drop = twoball.simulate(eps, mu, tau_ratio)
    linear = simulate_stack([mu], eps, tau_ratio)
    assert linear.h_icm == pytest.approx(drop.h_icm, rel=1e-12)
    assert linear.h1 / linear.h_icm == pytest.approx(drop.h1_over_icm, rel=1e-9)
    made = check_stack([mu], eps, tau_ratio, force="hertz", height=100.0)
    gap = made.x_start[-1] - made.height
    assert icm_chain(made)[-1] == pytest.approx(icm_height(100.0, gap, eps, eps, mu), rel=1e-12)


def _chain_by_root_finding(stack) -> list[float]:
    """The ICM chain found another way: each ball's path written out in absolute time and
    each meeting found by a root finder (the chain closes the distance at a constant speed)."""
    from scipy.optimize import brentq

    impact = np.sqrt(2.0 * stack.height)
    start, level, up = impact, 0.0, stack.eps[0] * impact  # ball i - 1 after its collision
    heights = [up**2 / 2]
    for i in range(1, stack.balls):

        def below(t, start=start, level=level, up=up):
            return level + up * (t - start) - (t - start) ** 2 / 2

        def falling(t, i=i):
            return stack.x_start[i] - t**2 / 2

        met = brentq(lambda t: falling(t) - below(t), start, start + 1e6, xtol=1e-14, rtol=1e-15)
        below_speed, speed = up - (met - start), -met
        m_below, m = stack.masses[i - 1], stack.masses[i]
        after = m_below * below_speed + m * speed - stack.eps[i] * m_below * (speed - below_speed)
        start, level, up = met, below(met), after / (m_below + m)
        heights.append(level + up**2 / 2)
    return heights


def test_the_icm_chain_with_gaps_against_a_root_finder():
    """Three and five balls with gaps: each ball's ICM apex is the one found by writing the
    paths out and finding each meeting with a root finder; released touching, every collision
    is at the floor and the chain is the textbook one (apexes v^2/2)."""
    for ratios, eps, gaps in (([0.3, 0.2], [0.9, 0.8, 0.7], [1.0, 3.0]), ([0.5] * 4, 0.85, 0.7)):
        made = check_stack(ratios, eps, gaps)
        assert icm_chain(made) == pytest.approx(_chain_by_root_finding(made), rel=1e-9)
    touching = check_stack([0.3, 0.2], 0.9, 0.0)
    impact = np.sqrt(2.0 * touching.height)
    chain = icm_chain(touching)
    assert chain[0] == pytest.approx((0.9 * impact) ** 2 / 2, rel=1e-14)
    assert chain == pytest.approx(_chain_by_root_finding(touching), rel=1e-9)


def test_the_icm_chain_of_two_balls_is_the_closed_form_for_any_gap():
    """Two balls, gaps from touching to the lower ball's bounces dying out before the upper
    arrives: the chain is :func:`twoball.model.icm_height`, the two-ball drop's h_ICM."""
    from twoball.model import icm_height

    rng = np.random.default_rng(7)
    for _ in range(200):
        eps, mu = rng.uniform(0.3, 1.0), 10 ** rng.uniform(-3, 0)
        made = check_stack([mu], eps, 10 ** rng.uniform(-2, 3), height=10 ** rng.uniform(0, 6))
        gap = made.x_start[1] - made.height
        expected = icm_height(made.height, gap, eps, eps, mu)
        assert icm_chain(made)[-1] == pytest.approx(expected, rel=1e-9, abs=1e-9 * made.height)


def test_the_icm_chain_asks_for_a_stack():
    with pytest.raises(ParameterError, match="stack must be a Stack, made by check_stack"):
        icm_chain([0.2])


def test_eight_balls_run_to_the_second_apex():
    result = simulate_stack([0.6] * 7, 0.9, 0.3)
    assert result.success and result.status is Status.DONE
    assert len(result.apexes[-1]) == 2
    assert all(count >= 1 for count in result.contacts_first)
    assert 0 < result.h1 <= result.h_icm * 10


def test_trajectory_is_the_apexes_and_forces_push():
    result = simulate_stack([0.2, 0.2], 0.9, 0.2, until="first")
    t1, h1 = result.apexes[-1][0]
    times = np.array([0.0, t1])
    sampled = simulate_stack([0.2, 0.2], 0.9, 0.2, until="first", t_eval=times).trajectory
    assert sampled.x[0] == pytest.approx(result.stack.x_start, rel=1e-15)
    assert sampled.x[1, -1] == pytest.approx(h1, rel=1e-12)
    assert abs(sampled.v[1, -1]) <= 1e-9
    forces = simulate_stack(
        [0.2, 0.2], 0.9, 0.2, until="first", t_eval=np.linspace(0, t1, 3001)
    ).trajectory.f
    assert forces.min() >= 0.0 and forces.max() > 1.0


@pytest.mark.parametrize("ratio", [1.0, 0.5, 0.2])
def test_three_balls_released_touching(ratio):
    """A zero gap: the contacts start active and unloaded; the run ends as asked, with the
    apex the energy allows; near-elastic at a low height too."""
    result = simulate_stack([ratio] * 2, 0.9, 0.0)
    assert result.success and len(result.apexes[-1]) == 2
    assert result.contacts_first[1] >= 1 and result.contacts_first[2] >= 1
    energy = float((result.stack.masses * result.stack.x_start).sum())
    assert result.h1 <= energy / result.stack.masses[-1]
    assert simulate_stack([ratio] * 2, 1.0, 0.0, height=10.0).success


def test_until_a_time_and_rest():
    running = simulate_stack([0.2, 0.2], 0.9, 0.2, until=50.0)
    assert running.end_time == pytest.approx(50.0) and running.status is Status.DONE
    resting = simulate_stack([0.5, 0.5], 0.3, 0.0, height=10.0, until=1e5)
    assert resting.status is Status.REST and resting.end_time < 1e5


TWO_GAPS = "tau_ratios must be one number or a flat sequence of exactly 2 (one per pair: 3 balls)"
# a set has no order and a generator is read once: each was taken as one item, "[0]", before
UNORDERED = (
    "must be one number or a flat sequence (a list, tuple or array, the balls from the floor up)"
)


@pytest.mark.parametrize(
    ("arguments", "words"),
    [
        (([], 0.9, 0.2), "mass_ratios must hold 1 to"),
        (([0.2, -1.0], 0.9, 0.2), "mass_ratios[1] must be a finite number in [1e-09, 1e+06]"),
        (([0.2, 0.2], [0.9, 0.8], 0.2), "eps must be one number or a flat sequence of exactly 3"),
        (([0.2, 0.2], [0.9], 0.2), "eps must be one number or a flat sequence of exactly 3"),
        (([0.2, 0.2], 1.5, 0.2), "eps must be a finite number in [0.01, 1]"),
        (([0.2, 0.2], 0.9, [0.1, 0.2, 0.3]), f"{TWO_GAPS}; got a sequence of 3"),
        (([0.2, 0.2], 0.9, [0.1]), f"{TWO_GAPS}; got a sequence of 1"),
        (([0.2, 0.2], 0.9, [[0.1, 0.2]]), f"{TWO_GAPS}; got a nested sequence"),
        (([[0.2, 0.3], [0.4]], 0.9, 0.2), "mass_ratios[0] must be a real number"),
        (([[0.2, 0.3], [0.4, 0.5]], 0.9, 0.2), "mass_ratios must be one number or a flat sequence"),
        (([[0.2, 0.3]], 0.9, 0.2), "mass_ratios must be one number or a flat sequence"),
        (([0.2, 0.2], 0.9, np.array([0.1])), "exactly 2"),
        (([0.2, 0.2], [0.9, 0.9, 0.0], 0.2), "eps[2] must be a finite number in [0.01, 1]"),
        (([0.2, 0.2], 0.9, float("nan")), "tau_ratios must be a finite number"),
        (([1e-5, 1e-5], 0.9, 0.2), "masses relative to ball 0"),
        (([0.2] * 16, 0.9, 0.2), "mass_ratios must hold 1 to 15"),
        (([0.5] * 3, 0.9, 0.0), "tau_ratios must be at least 1e-09 with 4 or more balls"),
        (({0.2, 0.3}, 0.9, 0.2), f"mass_ratios {UNORDERED}; got a set"),
        (((r for r in [0.2, 0.3]), 0.9, 0.2), f"mass_ratios {UNORDERED}; got a generator"),
        (([0.2, 0.3], frozenset([0.9]), 0.2), f"eps {UNORDERED}; got a frozenset"),
        (([0.2, 0.3], 0.9, iter([0.1, 0.2])), f"tau_ratios {UNORDERED}; got a list_iterator"),
    ],
)
def test_bad_input_names_the_parameter(arguments, words):
    with pytest.raises(ParameterError) as caught:
        simulate_stack(*arguments)
    assert words in str(caught.value)


def test_one_number_stands_for_every_contact_as_the_full_sequence_does():
    """A number is every pair's gap and every contact's eps; a sequence must name each (a list
    of one for three balls was shared out silently, as if entries had not been lost)."""
    shared = simulate_stack([0.2, 0.3], 0.9, 0.2)
    spelled = simulate_stack([0.2, 0.3], [0.9, 0.9, 0.9], [0.2, 0.2])
    assert (shared.h1, shared.h2, shared.contacts_first) == (
        spelled.h1,
        spelled.h2,
        spelled.contacts_first,
    )
    assert simulate_stack([0.2, 0.3], np.float64(0.9), np.array(0.2)).h2 == spelled.h2


def test_bad_options():
    with pytest.raises(ParameterError, match="force must be one of linear, hertz"):
        simulate_stack([0.2], 0.9, 0.2, force="spring")
    with pytest.raises(ParameterError, match="until must be"):
        simulate_stack([0.2], 0.9, 0.2, until="third")
    with pytest.raises(ParameterError, match="height must be"):
        simulate_stack([0.2], 0.9, 0.2, height=0.0)


def test_the_methods_are_one_mapping_of_one_signature(monkeypatch):
    """twoball.stacks.METHODS maps each force, then each name, to a solver of one signature,
    solve(stack, apexes, t_end, times, dense) -> StackResult, as twoball.METHODS does for two balls;
    simulate_stack runs what the mapping holds, and refuses a name it does not hold."""
    from twoball.stacks import METHODS, hertz
    from twoball.stacks.model import FORCES

    assert list(METHODS) == list(FORCES)
    assert list(METHODS["hertz"]) == list(hertz.METHODS) == ["compiled", "DOP853"]
    stack = check_stack([0.1], 0.9, 0.1, height=100.0, force="hertz")
    runs = {
        name: solve(stack, 1, math.inf, None, False) for name, solve in METHODS["hertz"].items()
    }
    for name, result in runs.items():
        assert (result.method, result.force, result.status) == (name, "hertz", Status.DONE)
    # two independent integrations of the same equations
    assert runs["compiled"].h1 == pytest.approx(runs["DOP853"].h1, rel=1e-9)
    pair = METHODS["linear"]["compiled"](check_stack([0.01], 0.9, 0.01), 2, math.inf, None, False)
    assert pair.method == "compiled" and pair.h2 == pytest.approx(CLOSE_UP.h2, rel=1e-8)

    def stub(stack, apexes, t_end, times, dense):
        return pair

    monkeypatch.setitem(METHODS["linear"], "compiled", stub)
    assert simulate_stack([0.3], 0.5, 0.5) is pair
    for force, method in (("linear", "DOP853"), ("hertz", "RK45")):
        with pytest.raises(ParameterError, match=f"method must be one of .* {force} force"):
            simulate_stack([0.2], 0.9, 0.2, force=force, method=method)
    with pytest.raises(ParameterError, match="'compiled' is the stacks' exact solver"):
        simulate_stack([0.2], 0.9, 0.2, method="exact")  # (the two-ball solver's name)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    ratios=st.lists(st.floats(0.01, 10.0), min_size=1, max_size=4),
    eps=st.floats(0.3, 1.0),
    gap=st.one_of(st.just(0.0), st.floats(0.0, 1.0)),
    height=st.floats(10.0, 1e5),
)
def test_any_stack_reaches_an_honest_answer(ratios, eps, gap, height):
    """Random stacks in the tested domain end as asked, at the second apex or at a proven rest
    (docs/stacks.md, "Why every damped stack ends"); every contact interval is ordered and the
    top ball never flies above what the energy at release allows."""
    if math.prod(ratios) < 1e-9 or math.prod(ratios) > 1e6:
        return
    if len(ratios) >= 3 and gap < 1e-9:
        return  # refused (test_bad_input_names_the_parameter)
    result = simulate_stack(ratios, eps, gap, height=height, throw=False)
    assert result.success, result.status
    for _, apex in result.apexes[-1]:  # none when the stack came to rest first
        assert apex <= _apex_bound(result.stack, "linear") * (1 + 1e-9)
    for contact in result.contacts:
        assert contact.start <= contact.end


def test_failure_is_loud(monkeypatch):
    """A run cut off by the phase limit raises unless throw=False, as simulate does (run with
    the kernels' Python functions, which read the limit when called)."""
    from twoball import jit
    from twoball.kernels import stack as stack_kernel

    monkeypatch.setattr(stack_kernel, "MAX_PHASES", 3)
    jit.use_python_kernels()
    try:
        with pytest.raises(SolverError, match="phase or step limit"):
            simulate_stack([0.2, 0.2], 0.9, 0.2)
        result = simulate_stack([0.2, 0.2], 0.9, 0.2, throw=False)
    finally:
        jit.use_compiled_kernels()
    assert not result.success and result.status is Status.PHASE_LIMIT


# --- the domain double precision can carry, as simulate's (docs/model.md, "Stacks of N balls") --


def _rounding_by_hand(height, masses, top):
    """docs/model.md's stack domain, written out here: 2.2e-16 max(X_top, 1) over the smallest
    overlap, max(sqrt(2H m_red), weight above) per contact (the floor's: sqrt(2H) and 1), and
    at least 1e-3 of it."""
    overlaps = [max(math.sqrt(2.0 * height), 1.0)]
    for c in range(1, len(masses)):
        reduced = masses[c] * masses[c - 1] / (masses[c] + masses[c - 1])
        overlaps.append(max(math.sqrt(2.0 * height * reduced), sum(masses[c:])))
    return 2.220446049250313e-16 * max(top, 1.0) * max(1.0 / min(overlaps), 1e-3)


def _largest_height_by_hand(masses):
    low, high = 0.0, 30.0
    for _ in range(100):
        middle = 0.5 * (low + high)
        if _rounding_by_hand(10.0**middle, masses, 10.0**middle) > 1e-6:
            high = middle
        else:
            low = middle
    return 10.0**low


@pytest.mark.parametrize("ratios", [[0.2], [0.2, 0.2], [1e-4, 1e-4], [3.0, 0.5, 2.0]])
def test_heights_beyond_the_domain_are_refused_as_simulate_refuses_them(ratios):
    """The largest height accepted is the one the formula of docs/model.md gives, evaluated here
    independently; H = 1e30 is refused, as simulate refuses it."""
    largest = _largest_height_by_hand(np.cumprod([1.0, *ratios]))
    check_stack(ratios, 0.9, 0.0 if len(ratios) < 3 else 1e-6, height=largest * 0.99)
    with pytest.raises(ParameterError, match="height must be at most") as caught:
        simulate_stack(ratios, 0.9, 0.2, height=1e30)
    assert f"{largest:.3g}" in str(caught.value) and "double precision" in str(caught.value)
    with pytest.raises(ParameterError, match="height must be at most"):
        check_stack(ratios, 0.9, 0.0 if len(ratios) < 3 else 1e-6, height=largest * 1.01)
    if len(ratios) == 1:  # two balls: the same limit as simulate's
        with pytest.raises(ParameterError) as single:
            twoball.simulate(0.9, ratios[0], 0.0, height=1e30)
        assert f"{largest:.3g}" in str(single.value)


def test_a_gap_beyond_the_domain_is_refused_as_simulate_refuses_it():
    """A gap of 1e7 gave h1 = 1.8e14 where simulate refuses gaps above 2.34e5 (mu = 0.2)."""
    with pytest.raises(ParameterError, match="tau_ratio must be at most 2.34e") as single:
        twoball.simulate(0.9, 0.2, 1e7)
    with pytest.raises(ParameterError, match="tau_ratios must be at most 2.34e") as pair:
        simulate_stack([0.2], 0.9, 1e7)
    assert str(single.value).split(" must")[1].split("(got")[0].replace("mu = 0.2", "") == (
        str(pair.value).split(" must")[1].split("(got")[0].replace("mass_ratios = [0.2]", "")
    )
    masses = [1.0, 0.2, 0.04]
    made = check_stack([0.2, 0.2], 0.9, [1e5, 1e4])
    assert _rounding_by_hand(1e4, masses, made.x_start[-1]) <= 1e-6
    with pytest.raises(ParameterError, match=r"tau_ratios \(their sum\) must be at most"):
        simulate_stack([0.2, 0.2], 0.9, [1e7, 1.0])


def test_two_balls_prove_rest_as_simulate_does():
    """eps = 0.01 under a ball 1e6 times heavier: simulate proves rest, the stack reached the
    phase limit (its cluster-energy test counts a slow overdamped mode far too loosely). Now
    both end at rest with no apex, and the stack's state at its end is simulate's then."""
    single = twoball.simulate(0.01, 1e6, 0.2, dense_output=True)
    pair = simulate_stack([1e6], 0.01, 0.2)
    assert single.status is Status.REST and pair.status is Status.REST
    assert pair.h1 is None and single.h1 is None
    assert pair.contacts_first == single.contacts_first
    sampled = simulate_stack([1e6], 0.01, 0.2, t_eval=[pair.end_time]).trajectory
    there = single.evaluate([pair.end_time])  # simulate's rest holds for every later time
    assert sampled.x[0, 0] == pytest.approx(there.x1[0], rel=1e-9, abs=1e-6)
    assert sampled.x[0, 1] == pytest.approx(there.x2[0], rel=1e-9, abs=1e-6)


def test_sample_times_outside_the_run_are_refused():
    with pytest.raises(ParameterError, match="t_eval must hold times >= 0"):
        simulate_stack([0.2], 0.9, 0.2, t_eval=[-1.0, 5.0])
    first = simulate_stack([0.2], 0.9, 0.2)
    with pytest.raises(ParameterError, match=r"t_eval must lie within the run's time span \[0, "):
        simulate_stack([0.2], 0.9, 0.2, t_eval=[5.0, 1e9])
    inside = simulate_stack([0.2], 0.9, 0.2, t_eval=[0.0, first.end_time]).trajectory
    assert inside.x[-1, 1] == pytest.approx(first.h2, rel=1e-12)
    with pytest.raises(ParameterError, match="t_eval must be a one-dimensional array"):
        simulate_stack([0.2], 0.9, 0.2, t_eval="abc")


def test_sample_times_past_the_end_are_nan_when_asked():
    """nan_past_end: a run to its second apex sampled in one pass, at times reaching past its
    end (not known beforehand). Two balls: simulate's own closed form inside, NaN past the end;
    three Hertz balls: the DOP853 reference method's samples inside (an integration in t, no
    code in common), NaN past the end for both; the runs end where unsampled runs do."""
    single = twoball.simulate(0.9, 0.2, 0.2, dense_output=True)
    times = np.linspace(0.0, 1.37 * single.end_time, 301)
    pair = simulate_stack([0.2], 0.9, 0.2, t_eval=times, nan_past_end=True)
    assert (pair.h1, pair.h2) == pytest.approx((single.h1, single.h2), rel=1e-12)
    inside = times <= pair.end_time
    assert 0 < inside.sum() < times.size
    exact = single.evaluate(times[inside])
    assert np.allclose(pair.trajectory.x[inside, 0], exact.x1, rtol=1e-10, atol=1e-9)
    assert np.allclose(pair.trajectory.x[inside, 1], exact.x2, rtol=1e-10, atol=1e-9)
    for rows in (pair.trajectory.x, pair.trajectory.v, pair.trajectory.f):
        assert np.isnan(rows[~inside]).all() and not np.isnan(rows[inside]).any()
    stack = ([0.3, 0.3], 0.8, 0.3)
    unsampled = simulate_stack(*stack, force="hertz")
    times = np.linspace(0.0, 1.37 * unsampled.end_time, 201)
    inside = times <= unsampled.end_time
    runs = [
        simulate_stack(*stack, force="hertz", method=m, t_eval=times, nan_past_end=True)
        for m in ("compiled", "DOP853")
    ]
    assert runs[0].apexes == unsampled.apexes and runs[0].end_time == unsampled.end_time
    # to h1 within 1e-7 of it (DOP853 is off by 2e-8 there); after, within DOP853's own error
    # in h2 (up to 2e-3 of it on the seeded drops, docs/accuracy.md, "The Hertz stack")
    early = times <= unsampled.apex_t[0]
    x, reference = runs[0].trajectory.x, runs[1].trajectory.x
    assert np.allclose(x[early], reference[early], rtol=0, atol=1e-7 * unsampled.h1)
    assert np.allclose(x[inside], reference[inside], rtol=0, atol=1e-3 * unsampled.h1)
    for run in runs:
        assert np.isnan(run.trajectory.x[~inside]).all()
        assert not np.isnan(run.trajectory.x[inside]).any()


@pytest.mark.parametrize(
    ("arguments", "words"),
    [
        (("0.2", 0.9, 0.2), "mass_ratios[0] must be a real number"),
        (([0.2], "0.9", 0.2), "eps must be a real number"),
        (([0.2], True, 0.2), "eps must be a real number"),
        (([0.2], 0.9, [True]), "tau_ratios[0] must be a real number"),
        (
            ([0.2], 0.9, [0.2, 0.2]),
            "tau_ratios must be one number or a flat sequence of exactly 1 (one per pair: 2 balls)",
        ),
    ],
)
def test_text_and_booleans_are_not_numbers(arguments, words):
    with pytest.raises(ParameterError) as caught:
        simulate_stack(*arguments)
    assert words in str(caught.value)
    with pytest.raises(ParameterError, match="height must be a real number"):
        simulate_stack([0.2], 0.9, 0.2, height="1e4")
    exact = simulate_stack([0.2], 0.9, 0.2)
    numpy_numbers = simulate_stack(np.array([0.2]), np.float64(0.9), np.float32(0.2))
    assert numpy_numbers.h1 == simulate_stack([0.2], 0.9, float(np.float32(0.2))).h1
    assert exact.h1 is not None


def test_a_phase_limit_says_what_is_true(monkeypatch):
    """The message said "e.g. an elastic floor, eps = 1" whatever eps was."""
    from twoball import jit
    from twoball.kernels import stack as stack_kernel

    monkeypatch.setattr(stack_kernel, "MAX_PHASES", 3)
    jit.use_python_kernels()
    try:
        with pytest.raises(SolverError) as damped:
            simulate_stack([0.2], 0.9, 0.2)
        with pytest.raises(SolverError) as elastic:
            simulate_stack([0.2], [1.0, 0.9], 0.2)
    finally:
        jit.use_compiled_kernels()
    assert "eps = 1" not in str(damped.value) and "phase or step limit" in str(damped.value)
    assert "the floor is elastic, eps = 1" in str(elastic.value)


def test_a_reused_cluster_store_gives_the_same_drop():
    """Drops of the same balls reuse the clusters' closed forms (stack._store_for); a drop run
    after others of the same balls (other heights, a time limit) is the same, to the bit, as
    with a fresh store, and a store is never shared by different balls."""
    from twoball.stacks import stack as stack_module

    drop = ([0.2, 0.3, 0.5], 0.6, 0.1)
    stack_module._STORES.clear()
    fresh = simulate_stack(*drop, height=30.0)
    assert len(stack_module._STORES) == 1
    simulate_stack(*drop, height=7.0)
    simulate_stack(*drop, height=300.0, until=20.0)
    simulate_stack([0.2, 0.3, 0.4], 0.6, 0.1, height=30.0)  # other balls: another store
    assert len(stack_module._STORES) == 2
    again = simulate_stack(*drop, height=30.0)
    assert (again.h1, again.h2, again.end_time) == (fresh.h1, fresh.h2, fresh.end_time)
    assert again.contacts == fresh.contacts and again.apexes == fresh.apexes


def test_contact_intervals_are_the_dataclass_s_own():
    """The linear stack writes its contact intervals straight into their instances
    (twoball.stacks.stack._intervals, bypassing the frozen dataclass's __init__ for speed):
    each must be what the constructor makes: equal, hashed and shown alike, frozen, its
    contact an int; and two balls' must be simulate's, field by field."""
    result = simulate_stack([0.2, 0.2], 0.9, 0.2)
    assert len(result.contacts) > 3
    for interval in result.contacts:
        made = twoball.ContactInterval(interval.contact, interval.start, interval.end)
        assert made == interval and hash(made) == hash(interval) and repr(made) == repr(interval)
        assert type(interval.contact) is int and interval.start <= interval.end
        with pytest.raises(dataclasses.FrozenInstanceError):
            interval.end = 0.0
    pair = sorted(simulate_stack([0.01], 0.9, 0.01).contacts, key=lambda i: i.start)
    single = twoball.simulate(0.9, 0.01, 0.01).contacts
    assert len(pair) == len(single) > 3
    for mine, theirs in zip(pair, single, strict=True):
        assert mine.contact == theirs.contact
        assert mine.start == pytest.approx(theirs.start, rel=1e-12)
        assert mine.end == pytest.approx(theirs.end, rel=1e-12)


def test_each_ball_s_apexes_are_the_kernel_s_rows_in_order():
    """simulate_stack splits the kernel's apex table (ball, time, height) by ball, row by row
    for a short table and by masks for a long one (twoball.stacks.stack._apexes_by_ball): both
    must give each ball its rows in the table's order."""
    for ratios in ([0.2, 0.2], [0.2] * 7):  # 12 rows; about 6 000
        result = simulate_stack(ratios, 0.9, 0.2)
        made = result.stack
        out = kernel.run(made.masses, made.zeta, made.x_start, 2, math.inf, False, _store_for(made))
        expected = [[] for _ in range(made.balls)]
        for ball, when, where in out.apexes.tolist():
            expected[int(ball)].append((when, where))
        assert result.apexes == expected
        assert sum(map(len, expected)) == out.apexes.shape[0]


def test_dense_output_evaluates_the_run_once_it_has_ended():
    """dense_output: a run sampled after its end is known, with no second run (the Stack
    scene's move). Linear: the kernel's own closed forms, the very samples of t_eval. Hertz
    (three balls): the cubics between the steps' ends within 2e-3 of the heights sampled on the
    series (3e-5 of the largest compression; straight lines between the same states are off by
    thousands), within 1 % of the largest force; a run kept dense ends where others do; the
    reference method and a run without it refuse."""
    for force in ("linear", "hertz"):
        stack = ([0.2, 0.2], 0.9, 0.2)
        run = simulate_stack(*stack, force=force, dense_output=True)
        unsampled = simulate_stack(*stack, force=force)
        assert run.apexes == unsampled.apexes and run.end_time == unsampled.end_time
        times = np.unique(
            np.concatenate(
                [np.linspace(0.0, run.end_time, 2001)]
                + [np.linspace(c.start, c.end, 9) for c in run.contacts]
            )
        )
        sampled = simulate_stack(*stack, force=force, t_eval=times).trajectory
        dense = run.evaluate(times)
        if force == "linear":
            for got, expected in zip(
                (dense.x, dense.v, dense.f), (sampled.x, sampled.v, sampled.f), strict=True
            ):
                np.testing.assert_array_equal(got, expected)
            continue
        assert np.abs(dense.x - sampled.x).max() < 2e-3
        assert np.abs(dense.v - sampled.v).max() < 0.05
        assert np.abs(dense.f - sampled.f).max() < 0.01 * np.abs(sampled.f).max()
        at_h1 = run.evaluate(run.apex_t[0])
        assert at_h1.x[0, -1] == pytest.approx(run.h1, rel=1e-15)
    with pytest.raises(ParameterError, match="t must lie within the run's time span"):
        run.evaluate(1.01 * run.end_time)
    with pytest.raises(ValueError, match="dense_output=True"):
        unsampled.evaluate(0.0)
    with pytest.raises(ParameterError, match="compiled methods only"):
        simulate_stack(*stack, force="hertz", method="DOP853", dense_output=True)


@pytest.mark.parametrize(
    ("force", "method"), [(f, m) for f, named in METHODS.items() for m in named]
)
def test_t_eval_in_any_order_is_sampled_in_that_order(force, method):
    """Every force and method gives t_eval's samples in the order asked, as the two-ball
    simulate and evaluate do (the Hertz methods, which sample in increasing order, gave the
    times sorted and each row of another time)."""
    given = np.array([2.5, 0.5, 4.0, 1.0, 0.5])
    run = simulate_stack([0.2, 0.2], 0.9, 0.2, force=force, method=method, t_eval=given)
    ordered = simulate_stack(
        [0.2, 0.2], 0.9, 0.2, force=force, method=method, t_eval=[0.5, 1.0, 2.5, 4.0]
    )
    at = {t: i for i, t in enumerate([0.5, 1.0, 2.5, 4.0])}
    rows = [at[t] for t in given]
    assert list(run.trajectory.t) == list(given)
    for field in ("x", "v"):
        assert np.array_equal(
            getattr(run.trajectory, field), getattr(ordered.trajectory, field)[rows]
        )


def test_evaluate_after_a_proven_rest_is_that_rest_or_says_how_to_sample_it():
    """A linear stack's dense output after its proven rest is the rest, as t_eval gives it and
    the two-ball Result.evaluate does (it was refused, with a hint to run further that could
    not help); the Hertz force's, which ends with its run, says to use t_eval."""
    stack = ([0.2], 0.3, 0.2)
    linear = simulate_stack(*stack, height=10, dense_output=True)
    assert linear.status is Status.REST
    times = [0.5 * linear.end_time, 1e4]
    sampled = simulate_stack(*stack, height=10, t_eval=times).trajectory
    evaluated = linear.evaluate(times)
    for field in ("x", "v", "f"):
        assert np.allclose(getattr(evaluated, field), getattr(sampled, field), atol=1e-12)
    assert np.allclose(evaluated.v[1], 0.0) and np.allclose(evaluated.f[1], [1.2, 0.2])  # weights
    hertz = simulate_stack(*stack, height=10, force="hertz", dense_output=True)
    assert hertz.status is Status.REST
    with pytest.raises(ParameterError, match="t_eval"):
        hertz.evaluate(1e4)


@pytest.mark.parametrize("gaps", [0.0, [0.0, 0.0], [0.0, 0.1], [0.1, 0.0]])
def test_balls_released_touching_push_only_once_something_pushes_them(gaps):
    """Balls released touching fall together with no force between them: no ball contact
    pushes before the floor's impact at sqrt(2H) (three touching balls had both pushing from
    t = 0), and two balls released touching count the ball contacts simulate counts (a contact
    of no length at t = 0 made them [1, 2] against simulate's [1, 1]: a researcher's trial)."""
    ratios = [0.2] if gaps == 0.0 else [0.2, 0.2]
    result = simulate_stack(ratios, 0.9, gaps, height=1e4)
    impact = math.sqrt(2.0 * 1e4)
    assert all(c.end > c.start for c in result.contacts)
    assert all(c.start >= impact * (1 - 1e-12) for c in result.contacts)
    first_bounce = [c for c in result.contacts if c.start < result.apex_t[0]]
    counted = [sum(c.contact == k for c in first_bounce) for k in range(len(ratios) + 1)]
    assert counted == result.contacts_first
    if gaps == 0.0:
        drop = twoball.simulate(0.9, 0.2, 0.0, height=1e4)
        assert result.contacts_first == drop.contacts_first
        ball = [c for c in result.contacts if c.contact == 1]
        # (a root where the overlap grows as the cube of the time since the impact: each
        # solver's to ~1e-10 of the 3-unit contact)
        assert ball[0].start == pytest.approx(drop.contacts[1].start, abs=1e-8)


@pytest.mark.parametrize("bound", [1e-320, 5e-324, 1e-310])
@pytest.mark.parametrize("rate", [0.0, -0.0])
def test_a_step_bounded_by_a_subnormal_curvature_is_its_quadratic_s_root(bound, rate):
    """The certified step is the root of f + f' h - bound h^2 / 2, sqrt(2 f / bound) with f' = 0
    (computed here at 40 digits). A cluster at rest for a thousand time units bounds its
    curvature by a subnormal number, and 2 bound f underflowed: the step was 0, a run STUCK."""
    import mpmath

    from twoball.kernels.phases import _safe_step

    f = 1e-3
    exact = mpmath.sqrt(2 * mpmath.mpf(f) / mpmath.mpf(bound))
    assert _safe_step(f, rate, bound) == pytest.approx(float(exact), rel=1e-12)


def test_a_ball_falling_onto_a_stack_at_rest_for_a_thousand_time_units():
    """The top ball falls from its first apex (~1.6e7) onto three balls that have come to rest:
    their motion decays into subnormal numbers over the fall, and the run ended STUCK there
    (a random search's find). The balls below rest at their static overlaps -W_c (docs/model.md,
    "Stacks of N balls", the domain), so the top ball touches after a free fall from its apex."""
    ratios = [0.01267, 0.0803, 28.11]
    eps = [0.2664727070430738, 0.08127696332023072, 0.32747257073101677, 0.9178657419179851]
    result = simulate_stack(ratios, eps, 2077.3, height=27)
    lower = check_stack(ratios, eps, 2077.3, height=27).masses[:3]
    rest = np.cumsum(-np.cumsum(lower[::-1])[::-1])  # heights from the overlaps -W_c
    apex_t, apex_h = result.apex_t[0], result.apex_h[0]
    touch = apex_t + math.sqrt(2.0 * (apex_h - rest[-1]))
    below = simulate_stack(ratios, eps, 2077.3, height=27, t_eval=[touch - 1.0]).trajectory
    assert below.x[0, :3] == pytest.approx(rest, abs=1e-9)
    assert below.v[0, :3] == pytest.approx(0.0, abs=1e-9)
    second = next(c for c in result.contacts if c.contact == 3 and c.start > apex_t)
    assert second.start == pytest.approx(touch, rel=1e-9)
    assert result.apex_h[1] < apex_h  # damped: the energy never rises


@pytest.mark.parametrize("force", ["linear", "hertz"])
def test_contacts_are_listed_in_the_order_they_begin(force):
    """Every force lists its contact intervals by start, as the two-ball drop does (the linear
    kernel lists one when it ends: a long floor contact came after the ball contacts within
    it); each contact's own intervals follow each other without overlapping."""
    result = simulate_stack([0.2, 0.2], 0.9, 0.2, force=force)
    starts = [interval.start for interval in result.contacts]
    assert starts == sorted(starts) and len(starts) > 3
    for contact in range(3):
        own = [(c.start, c.end) for c in result.contacts if c.contact == contact]
        assert all(end <= start for (_, end), (start, _) in zip(own, own[1:], strict=False))


def test_a_stack_that_never_switches_again_is_at_rest():
    """A heavy ball on a light one under two very light balls (a researcher's trial): the last
    phase, the lower balls pressed together, is certified to infinity, with no contact to switch
    and no ball to fly. That is a rest (it ended DONE at t = inf, no apex and no reason). From
    its end on, every state is the static rest: no speed, and each contact pressed by exactly
    the weight above it (docs/model.md, "Stacks of N balls": f_c = sum of the masses above)."""
    ratios = [7.587320770044136, 0.018440037514196074, 0.0003249705022031509, 1.1485495516829e-4]
    result = simulate_stack(ratios, 0.10791136768877864, 1e-9, height=0.702557003277761)
    assert result.status is Status.REST and math.isfinite(result.end_time)
    assert result.h1 is None and result.reason
    later = result.end_time + np.array([1e3, 1e6])
    rest = simulate_stack(
        ratios, 0.10791136768877864, 1e-9, height=0.702557003277761, t_eval=later
    ).trajectory
    masses = result.stack.masses
    weights = np.cumsum(masses[::-1])[::-1]  # above each contact, the floor's included
    assert np.abs(rest.v).max() <= 1e-9 * np.sqrt(2 * result.stack.height)
    for forces in rest.f:  # (to the rounding of the largest, the floor's)
        assert forces == pytest.approx(weights, rel=1e-9, abs=1e-14 * weights[0])


@pytest.mark.parametrize("flag", ["dense_output", "throw", "nan_past_end"])
@pytest.mark.parametrize("value", ["no", 0, None, 1.0])
def test_a_switch_is_true_or_false(flag, value):
    """A switch given anything but True or False is refused, naming it, by both entry points
    ('no' had been taken as true, a researcher's trial); numpy's booleans are booleans."""
    with pytest.raises(ParameterError, match=f"{flag} must be True or False; got"):
        simulate_stack([0.2, 0.2], 0.9, 0.2, **{flag: value})
    if flag != "nan_past_end":  # (the two-ball simulate has no such switch)
        with pytest.raises(ParameterError, match=f"{flag} must be True or False; got"):
            twoball.simulate(0.9, 0.2, 0.2, **{flag: value})
    assert simulate_stack([0.2, 0.2], 0.9, 0.2, until="first", **{flag: np.bool_(True)}).success
