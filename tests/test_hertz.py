"""The Hertz force with Hunt-Crossley damping (twoball.stacks.hertz): restitution against an
independent integration, energy, and the textbook limit."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from twoball.errors import Status
from twoball.stacks import hertz, icm_chain, simulate_stack


def _restitution_in_free_space(eps: float, mass1: float, mass2: float, speed: float) -> float:
    """Two balls meeting at ``speed`` with no gravity, integrated here from the force law
    f = delta^(3/2) (1 + lam delta'), never pulling, with lam = Lambda(eps) / speed."""
    lam = hertz.damping_factor(eps) / speed
    reduced = mass1 * mass2 / (mass1 + mass2)

    def rhs(_t, y):
        delta, rate = y
        force = max(delta, 0.0) ** 1.5 * max(1.0 + lam * rate, 0.0)
        return [rate, -force / reduced]

    def separated(_t, y):
        return y[0] if 1.0 + lam * y[1] > 0.0 else -1.0

    separated.terminal, separated.direction = True, -1.0
    solution = solve_ivp(
        rhs, (0.0, 1e3), [0.0, speed], method="Radau", rtol=1e-12, atol=1e-14,
        events=separated,
    )  # fmt: skip
    return -solution.y_events[0][0][1] / speed


@pytest.mark.parametrize("eps", [0.3, 0.7, 0.95])
@pytest.mark.parametrize(("mass1", "mass2", "speed"), [(1.0, 0.3, 7.3), (0.01, 5.0, 300.0)])
def test_an_isolated_contact_gives_back_eps(eps, mass1, mass2, speed):
    """The calibration holds for any masses and speed (the Hertz scaling, docs/stacks.md)."""
    assert _restitution_in_free_space(eps, mass1, mass2, speed) == pytest.approx(eps, abs=1e-8)


def test_the_floor_contact_in_a_stack_gives_back_eps():
    """At a height where gravity during the contact is negligible (t_c / v ~ 4e-5), ball 0
    leaves the floor at eps times its impact speed (ball 1 arrives after it left)."""
    first = simulate_stack([0.5], 0.7, 3.0, height=1e8, force="hertz", until="first")
    floor = next(c for c in first.contacts if c.contact == 0)
    after = simulate_stack(
        [0.5], 0.7, 3.0, height=1e8, force="hertz", until="first", t_eval=[floor.end]
    )
    assert after.trajectory.v[0, 0] / math.sqrt(2e8) == pytest.approx(0.7, rel=1e-4)


def _energy(result) -> np.ndarray:
    masses = result.stack.masses
    x, v = result.trajectory.x, result.trajectory.v
    eta = np.concatenate([x[:, :1], np.diff(x, axis=1)], axis=1)
    delta = np.maximum(-eta, 0.0)
    return 0.5 * (masses * v**2).sum(axis=1) + (masses * x).sum(axis=1) + 0.4 * (delta**2.5).sum(1)


def _times(result) -> np.ndarray:
    inside = [np.linspace(c.start, c.end, 25) for c in result.contacts]
    return np.unique(np.concatenate([np.linspace(0.0, result.end_time, 2001), *inside]))


def test_energy_never_rises():
    first = simulate_stack([0.2, 0.2], 0.8, 0.2, force="hertz")
    sampled = simulate_stack([0.2, 0.2], 0.8, 0.2, force="hertz", t_eval=_times(first))
    energy = _energy(sampled)
    assert np.diff(energy).max() <= 1e-9 * energy[0]
    assert energy[-1] < 0.99 * energy[0]
    assert (sampled.h1, sampled.h2) == (first.h1, first.h2)  # sampling changes nothing


@pytest.mark.parametrize(("ratios", "height"), [([0.3], 1e4), ([0.2, 0.2], 1e5)])
def test_elastic_contacts_conserve_energy(ratios, height):
    """Sampled through every contact to the second apex: measured 1.1e-13 and 2.8e-12, the
    overlaps here rebuilt from heights of 1.6e5 (the DOP853 reference method: 3e-9 and 3e-7;
    heights of 1e6 rounded step by step, before the compiled path carried them as compensated
    sums: 2e-10)."""
    first = simulate_stack(ratios, 1.0, 0.5, force="hertz", height=height)
    sampled = simulate_stack(ratios, 1.0, 0.5, force="hertz", height=height, t_eval=_times(first))
    energy = _energy(sampled)
    assert np.ptp(energy) <= 5e-12 * energy[0]


@pytest.mark.parametrize("height", [1e2, 5e4, 1e5])
def test_a_lone_elastic_floor_contact_gives_back_the_energy(height):
    """Ball 0's energy before and after its first floor contact, alone (ball 1 meets it only
    after it has left the floor): measured 1.5e-16 to 4.4e-16, one to three ulps of the energy
    (the compiled DOP853 before the Taylor series: 1e-15 to 6e-15; the DOP853 reference method:
    5e-11 to 1e-10, the error that put h2 off)."""
    first = simulate_stack([0.3], 1.0, 5.0, force="hertz", height=height, until="first")
    floor = next(c for c in first.contacts if c.contact == 0)
    ball = next(c for c in first.contacts if c.contact == 1)
    assert ball.start > floor.end
    times = [0.5 * floor.start, 0.5 * (floor.end + ball.start)]
    sampled = simulate_stack(
        [0.3], 1.0, 5.0, force="hertz", height=height, until="first", t_eval=times
    )
    x, v = sampled.trajectory.x[:, 0], sampled.trajectory.v[:, 0]
    energy = 0.5 * v**2 + x
    assert abs(energy[1] - energy[0]) <= 2e-15 * energy[0]


@pytest.mark.parametrize(
    ("ratios", "eps", "gaps"),
    [([0.2], 0.9, 0.2), ([0.01], 0.9, 0.01), ([0.3], 1.0, 0.5), ([0.2, 0.2], 0.9, 0.2)],
)
def test_the_compiled_path_agrees_with_the_dop853_reference(ratios, eps, gaps):
    """Same contacts, same h1 to 1e-9; h2 to 2e-6, the DOP853 method's own error there
    (measured against the 30-digit reference: up to 1e-6, docs/accuracy.md)."""
    fast = simulate_stack(ratios, eps, gaps, force="hertz")
    slow = simulate_stack(ratios, eps, gaps, force="hertz", method="DOP853")
    assert fast.contacts_first == slow.contacts_first
    assert len(fast.contacts) == len(slow.contacts)
    assert fast.h1 == pytest.approx(slow.h1, rel=1e-9)
    assert fast.h2 == pytest.approx(slow.h2, rel=2e-6)


def test_an_unknown_method_is_refused():
    from twoball.errors import ParameterError

    with pytest.raises(ParameterError, match="method must be one of compiled, DOP853"):
        simulate_stack([0.2], 0.9, 0.2, force="hertz", method="RK45")


def test_light_elastic_ball_approaches_the_icm():
    result = simulate_stack([1e-4], 1.0, 3.0, height=1e8, force="hertz", until="first")
    assert result.h1 == pytest.approx(icm_chain(result.stack)[-1], rel=2e-3)
    assert result.contacts_first[1] == 1


def test_a_three_ball_stack_reaches_its_second_apex():
    result = simulate_stack([0.2, 0.2], 0.9, 0.2, force="hertz")
    assert result.success and len(result.apexes[-1]) == 2
    assert all(count >= 1 for count in result.contacts_first)
    assert result.stack.tau_f == pytest.approx(hertz.floor_contact_time(0.9, 1e4))


def test_a_heavy_stack_comes_to_a_proven_rest():
    """Heavy, strongly damped balls on a light one never fly apart: the run ends at rest, proven
    from the energy (hertz._settled). Sampling on, well past that moment, must show every
    contact still compressed (an integration independent of the proof's arithmetic)."""
    ratios, eps = [4.28, 4.31], 0.05
    result = simulate_stack(ratios, eps, 0.0, force="hertz")
    assert result.status.name == "REST" and result.h2 is None
    later = np.linspace(result.end_time, result.end_time + 300.0, 301)
    sampled = simulate_stack(ratios, eps, 0.0, force="hertz", until=later[-1], t_eval=later)
    assert sampled.status.name == "REST" and np.isfinite(sampled.trajectory.x).all()
    x = sampled.trajectory.x
    eta = np.concatenate([x[:, :1], np.diff(x, axis=1)], axis=1)
    assert eta.max() < 0.0
    energy = _energy(sampled)
    assert np.diff(energy).max() <= 1e-9 * abs(energy).max()


def test_four_hertz_balls_released_touching():
    """A Hertz force is continuous at first touch, so touching balls carry no limit (the linear
    force refuses gaps below 1e-9 from four balls on)."""
    from twoball.errors import ParameterError

    with pytest.raises(ParameterError, match="tau_ratios must be at least 1e-09"):
        simulate_stack([0.5, 0.5, 0.5], 0.9, 0.0)
    first = simulate_stack([0.5, 0.5, 0.5], 0.9, 0.0, height=10.0, force="hertz")
    assert first.success and len(first.apexes[-1]) == 2
    sampled = simulate_stack(
        [0.5, 0.5, 0.5], 0.9, 0.0, height=10.0, force="hertz", t_eval=_times(first)
    )
    energy = _energy(sampled)
    assert np.diff(energy).max() <= 1e-9 * energy[0]


def test_hertz_refuses_what_it_cannot_carry():
    from twoball.errors import ParameterError

    with pytest.raises(ParameterError, match="eps must be at least 0.05 with the hertz force"):
        simulate_stack([0.2], 0.01, 0.2, force="hertz")


@pytest.mark.slow  # about 25 s
@settings(max_examples=12, deadline=None)
@given(
    ratios=st.lists(st.floats(0.05, 5.0), min_size=1, max_size=3),
    eps=st.floats(0.05, 1.0),
    gap=st.floats(0.0, 1.0),
)
def test_any_hertz_stack_reaches_an_honest_answer(ratios, eps, gap):
    """Lighter balls on heavier ones (the app's range) finish; heavy balls on light ones finish
    or, nearly elastic and released touching, may run out of steps, loudly (docs/stacks.md)."""
    result = simulate_stack(ratios, eps, gap, force="hertz", throw=False)
    if max(ratios) <= 1.0:
        assert result.success, result.status  # which includes: no apex above what energy allows
    else:
        assert result.success or result.status == Status.PHASE_LIMIT, result.status


def test_the_check_values_of_the_specification():
    """docs/model.md, "The Hertz force": Lambda(0.9), Lambda(0.5), the elastic duration."""
    assert hertz.damping_factor(0.9) == pytest.approx(0.16648, abs=1e-5)
    assert hertz.damping_factor(0.5) == pytest.approx(1.43275, abs=1e-5)
    assert hertz.floor_contact_time(1.0, 0.5) == pytest.approx(3.218, abs=1e-3)


def test_an_eps_within_rounding_of_one_is_elastic():
    """eps one ulp below 1 lies above the undamped contact's integrated restitution (1 - 4e-13):
    the root finder had no bracket and raised (found by the property test above)."""
    eps = math.nextafter(1.0, 0.0)
    assert hertz.damping_factor(eps) == 0.0
    assert simulate_stack([1.0], eps, 0.0, force="hertz").h1 > 0.0


def test_hertz_refuses_heights_beyond_the_domain():
    """H = 1e30 ended in a traceback (RuntimeError: DOP853 failed); now refused up front, as
    the linear force is, with the largest height (docs/model.md, "Stacks of N balls")."""
    from twoball.errors import ParameterError

    with pytest.raises(ParameterError, match="height must be at most .* and the hertz force"):
        simulate_stack([0.2], 0.9, 0.2, force="hertz", height=1e30)
    with pytest.raises(ParameterError, match="tau_ratios must be at most"):
        simulate_stack([0.2], 0.9, 1e7, force="hertz")  # ran 3 minutes, then failed


def test_hertz_refuses_overdamped_slow_impacts_with_the_smallest_height():
    """H = 1e-9 ran 50 s and failed: the damping lam = Lambda(eps) / v, calibrated at the impact
    speed v, overdamps the settling. The smallest height in the message is where lam, computed
    here from the ICM chain's closing speeds, is 50."""
    from twoball.errors import ParameterError
    from twoball.stacks import check_stack

    with pytest.raises(ParameterError, match="height must be at least") as caught:
        simulate_stack([0.2], 0.9, 0.2, force="hertz", height=1e-9)
    smallest = float(str(caught.value).split("at least ")[1].split(" ")[0])
    impact = math.sqrt(2.0 * smallest)
    closing = impact + 0.9 * impact  # ball 1 falling at impact meets ball 0 rising at 0.9 impact
    lam = hertz.damping_factor(0.9) / min(impact, closing)
    assert lam == pytest.approx(50.0, rel=2e-3)
    check_stack([0.2], 0.9, 0.2, force="hertz", height=smallest * 1.01)
    with pytest.raises(ParameterError, match="height must be at least"):
        check_stack([0.2], 0.9, 0.2, force="hertz", height=smallest * 0.99)
    with pytest.raises(ParameterError, match=r"\[1e-09, 10000\] with the hertz force"):
        simulate_stack([1e6], 0.9, 0.2, force="hertz")  # ran a minute, then failed


def test_a_hertz_stack_checked_is_the_stack_its_run_starts_from():
    """check_stack(..., force="hertz") gives the stack a Hertz run starts from: its gaps in the
    Hertz floor contact time (not the linear one, 15 % apart here), each ball released at the
    height the gaps above it give, and its ICM chain the run's h_ICM (a researcher took
    check_stack's for the run's)."""
    from twoball.stacks import check_stack
    from twoball.stacks.model import floor_contact_time as linear_contact_time

    checked = check_stack([0.2, 0.3], 0.9, [1.0, 0.5], height=100.0, force="hertz")
    run = simulate_stack([0.2, 0.3], 0.9, [1.0, 0.5], height=100.0, force="hertz", until="first")
    assert checked.tau_f == run.stack.tau_f
    np.testing.assert_array_equal(checked.x_start, run.stack.x_start)
    assert abs(checked.tau_f / linear_contact_time(checked.zeta[0]) - 1) > 0.05
    # each ball released where free fall from it reaches the floor delay_i after ball 0 does,
    # delay_i the gaps below it in units of tau_f: H + sqrt(2H) delay + delay^2 / 2
    impact = math.sqrt(2.0 * 100.0)
    for ball, delay in enumerate(np.cumsum([0.0, 1.0, 0.5]) * checked.tau_f):
        expected = 100.0 + impact * delay + delay * delay / 2
        assert checked.x_start[ball] == pytest.approx(expected, rel=1e-13)
    assert icm_chain(checked)[-1] == run.h_icm


def test_an_integrator_failure_is_a_solver_error(monkeypatch):
    """DOP853 failing in a contact phase raised a RuntimeError (a traceback on the command
    line); it is the run's status FAILED: SolverError, or success False with throw=False."""
    from twoball.errors import SolverError

    class Failing(hertz.DOP853):
        def step(self):
            self.status = "failed"
            return "Required step size is less than spacing between numbers."

    monkeypatch.setattr(hertz, "DOP853", Failing)
    with pytest.raises(SolverError, match="integrator failed"):
        simulate_stack([0.2], 0.9, 0.2, force="hertz", method="DOP853")
    result = simulate_stack([0.2], 0.9, 0.2, force="hertz", throw=False, method="DOP853")
    assert not result.success and result.status is Status.FAILED and result.h1 is None


def test_the_step_budget_bounds_a_run_that_cannot_end(monkeypatch):
    """A run to a time far beyond the second apex bounced on (Hunt-Crossley grows elastic as
    the impacts slow) for 100 000 steps, 90 s. The budget is counted, not timed: a run that
    exceeds it stops at MAX_STEPS steps, loudly."""
    from twoball.errors import SolverError

    calls = []
    real = hertz.DOP853.step

    def counted(self):
        calls.append(1)
        return real(self)

    monkeypatch.setattr(hertz, "MAX_STEPS", 500)
    monkeypatch.setattr(hertz.DOP853, "step", counted)
    with pytest.raises(SolverError, match="phase or step limit") as caught:
        simulate_stack([0.2], 0.9, 0.2, force="hertz", until=1e300, method="DOP853")
    assert "eps = 1" not in str(caught.value)
    assert len(calls) <= 500


def test_the_compiled_path_stops_at_its_step_budget_too():
    """An elastic floor never lets the stack settle: run to a time far beyond the second apex,
    the compiled path ends at its budget (hertz_kernel.MAX_STEPS), loudly and within seconds,
    with the clock well past the second apex."""
    import time

    from twoball.errors import SolverError

    start = time.perf_counter()
    with pytest.raises(SolverError, match="phase or step limit") as caught:
        simulate_stack([0.2], 1.0, 0.2, force="hertz", until=1e300)
    assert time.perf_counter() - start < 20.0
    assert "eps = 1" in str(caught.value)
    second = simulate_stack([0.2], 1.0, 0.2, force="hertz").end_time
    assert caught.value.result.end_time > 10 * second


def _stored_references() -> list[dict]:
    import csv
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "docs" / "hertz_vs_truth.csv"
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


def _case(row: dict) -> dict:
    return {
        "mass_ratios": [float(r) for r in row["mass_ratios"].split()],
        "eps": float(row["eps"]),
        "tau_ratios": float(row["tau_ratios"]),
        "height": float(row["height"]),
    }


def test_the_compiled_path_against_the_30_digit_reference():
    """Every drop of docs/hertz_vs_truth.csv (docs/accuracy.md, "The Hertz stack"), the solver as
    it is now against the stored reference values: equal contact counts, h1 and h2 within the
    rule (1e-10 or ten times its conditioning) on all (the compiled DOP853 before the Taylor
    series: three drops outside in h2, four to seven times)."""
    from twoball.studies.hertz_truth import TOLERANCE_H
    from twoball.studies.stack_comparison import stack_against

    rows = _stored_references()
    assert len(rows) >= 20 and {int(r["balls"]) for r in rows} == {2, 3, 4}
    assert any(float(r["eps"]) == 1.0 for r in rows)
    for stored in rows:
        conditioning = (float(stored["cond_h1"]), float(stored["cond_h2"]))
        row = stack_against(_case(stored), stored, conditioning, force="hertz")
        assert row.contacts_first == row.contacts_first_truth, (stored, row)
        assert row.within(floor=TOLERANCE_H), (stored, row)


def test_a_taylor_step_sees_past_vanishing_last_terms():
    """At a touch the series are lacunary (rho'' ~ rho^4 in tau: from rho = 0 only every fifth
    coefficient is nonzero), so their last two terms can vanish while the radius of convergence
    is finite: the step must still be the tolerance's root of it (Jorba and Zou's rule on the
    last two terms alone gave an infinite step here, and at order 24 a step six times too long
    on a real drop)."""
    from twoball.kernels import taylor

    radius = 0.01
    series = np.zeros((2, taylor.ORDER + 1))
    series[1, 1 : taylor.ORDER + 1 : 5] = radius ** -np.arange(1, taylor.ORDER + 1, 5)
    series[1, taylor.ORDER - 1 :] = 0.0
    step = taylor._taylor_step(series, np.ones(2), np.array([1]))
    last = max(k for k in range(taylor.ORDER + 1) if series[1, k] != 0.0)
    assert last < taylor.ORDER - 1
    assert step == pytest.approx(radius * taylor.TOLERANCE ** (1.0 / taylor.ORDER), rel=0.3)
    assert (step / radius) ** (last + 5) <= taylor.TOLERANCE  # the first term left out


def test_the_hertz_rule_refuses_what_it_should():
    from twoball.studies.hertz_truth import TOLERANCE_H
    from twoball.studies.stack_comparison import StackComparison

    row = StackComparison("2 1", "2 1", 1e-13, 9e-11, cond_h1=1e-15, cond_h2=1e-15)
    assert row.within(floor=TOLERANCE_H)
    assert not replace(row, rel_err_h2=1.1e-10).within(floor=TOLERANCE_H)
    ten_times = replace(row, rel_err_h2=1.1e-10, cond_h2=2e-11)  # ten times its conditioning
    assert ten_times.within(floor=TOLERANCE_H)
    assert not replace(row, contacts_first="3 1").within(floor=TOLERANCE_H)


@pytest.mark.slow  # about 5 s
def test_one_reference_value_recomputed():
    """The 30-digit reference (twoball.studies.hertz_truth) recomputes a stored elastic drop to
    20 digits, and a damped one to 1e-12: a damped contact's lam is calibrated by scipy's root
    finder (twoball/stacks/hertz_contact.py), whose last digits differ between machines and
    libraries (here h1 moved by 1.7e-14 with them), so the reference's input, not its
    arithmetic, differs there."""
    import mpmath

    from twoball.studies import hertz_truth

    pairs = [r for r in _stored_references() if r["balls"] == "2"]
    elastic = min((r for r in pairs if r["eps"] == "1.0"), key=lambda r: float(r["height"]))
    damped = min((r for r in pairs if r["eps"] != "1.0"), key=lambda r: float(r["height"]))
    for stored, tolerance in ((elastic, 1e-20), (damped, 1e-12)):
        fresh = hertz_truth.reference(_case(stored))
        assert fresh["contacts_first_truth"] == stored["contacts_first_truth"]
        with mpmath.workdps(40):
            for name in ("h1_truth", "h2_truth"):
                error = abs(mpmath.mpf(fresh[name]) / mpmath.mpf(stored[name]) - 1)
                assert error < tolerance, (stored["eps"], name, error)


def test_the_slider_s_damping_factors_are_the_calibrated_ones():
    """The damping factors shipped for the app's eps slider (k / 100, k = 30 to 100) are what
    the calibration computes, to the bit; an eps between two steps is calibrated."""
    from twoball.stacks import hertz_contact

    for k, factor in zip(hertz_contact.SLIDER_STEPS, hertz_contact.SLIDER_FACTORS, strict=True):
        assert hertz_contact._calibrated(k / 100) == factor, k
        assert hertz.damping_factor(k / 100) == factor
    between = hertz.damping_factor(0.515)
    assert between == hertz_contact._calibrated(0.515)
    assert hertz.damping_factor(0.52) < between < hertz.damping_factor(0.51)


def test_a_root_whose_bracket_values_underflow_is_found():
    """Five equal elastic balls, three times heavier each: the switching root's regula falsi
    halved both ends' values to zero and divided by their difference, and the compiled run
    raised ZeroDivisionError (a researcher's trial; 23 of 810 stacks of 6-8 balls). It now
    halves the bracket there, and agrees with the reference integrator on h1. (Not on h2,
    whose drop is chaotic: a gap 1e-10 larger moves the compiled h2 by 9 %.)"""
    stack = ([3.0] * 5, 1.0, 0.435)
    compiled = simulate_stack(*stack, force="hertz")
    reference = simulate_stack(*stack, force="hertz", method="DOP853")
    assert compiled.status is Status.DONE and reference.status is Status.DONE
    assert compiled.h1 == pytest.approx(reference.h1, rel=1e-8)


def test_a_time_change_of_many_small_overlaps_keeps_its_clock():
    """Eight light balls released touching (a researcher's trial): seven overlaps of 1e-16 to 1
    made the time change's J = 1e-25, the clock's last series coefficients underflowed to zero,
    the step was taken as infinite and the run failed with its clock at 3e260 (docs/stacks.md,
    "Why a Taylor series of the time-changed motion"). Now it agrees with the reference
    integrator on the first apex (measured: 2.2e-9, the DOP853 method's own error)."""
    stack = ([0.1] * 7, 0.9, 0.0)
    compiled = simulate_stack(*stack, force="hertz", height=1.0, until="first")
    reference = simulate_stack(*stack, force="hertz", height=1.0, until="first", method="DOP853")
    assert compiled.status is Status.DONE and reference.status is Status.DONE
    assert compiled.h1 == pytest.approx(reference.h1, rel=1e-8)
    assert compiled.t1 == pytest.approx(reference.t1, rel=1e-9)


def test_a_time_change_of_many_large_overlaps_keeps_its_clock():
    """Eight elastic balls, three times heavier each, from H = 1e8: seven overlaps of 1e4 made
    J = 1e14 at the top ball's touch, the series overflowed and the run failed at that touch
    (ZeroDivisionError, the damped drop FAILED). Through the first impact, every contact
    closed, the energy is now conserved (measured: 1.3e-15)."""
    times = [0.0, 14200.0]  # the top ball touches at 14150
    result = simulate_stack(
        [3.0] * 7, 1.0, 0.435, force="hertz", height=1e8, until=times[-1], t_eval=times
    )
    assert {c.contact for c in result.contacts} == set(range(8))
    energy = _energy(result)
    assert abs(energy[1] - energy[0]) <= 1e-13 * energy[0]


def test_a_heavy_ball_sinking_into_a_light_one_proves_its_rest_within_the_budget():
    """A ball 853.6 times heavier than ball 0, eps 0.05, H 0.3: Hunt-Crossley holds the weight
    with its damping, so the pair sinks overdamped into its static compression (about 1 400
    steps a time unit). The rest test kept only half the top contact's margin, (3/10)
    W_top^(5/3), for the integration's error: the energy reached it after t = 300, past the
    300 000 steps (PHASE_LIMIT at t = 245); with the margin less the measured error it is proven
    at t = 62. Checked in the test's own arithmetic: the sampled energy there lies below the
    least potential plus (3/5) W_top^(5/3) (docs/model.md, "The Hertz force", rest), and both
    contacts stay compressed after."""
    ratios, eps, gap, height = [853.6], 0.05, 0.5, 0.3
    result = simulate_stack(ratios, eps, gap, height=height, force="hertz", throw=False)
    assert result.status.name == "REST"
    later = np.linspace(result.end_time, result.end_time + 5.0, 6)
    sampled = simulate_stack(
        ratios, eps, gap, height=height, force="hertz", until=later[-1], t_eval=later
    )
    weights = np.cumsum(sampled.stack.masses[::-1])[::-1]
    least = -0.6 * (weights ** (5.0 / 3.0)).sum()
    assert (_energy(sampled) < least + 0.6 * weights[-1] ** (5.0 / 3.0)).all()
    x = sampled.trajectory.x
    assert np.concatenate([x[:, :1], np.diff(x, axis=1)], axis=1).max() < 0.0


def test_a_contact_touching_slowly_at_a_large_height_is_integrated():
    """Seven balls from H = 2.9e8 (a researcher's trial; 0.3 % of random stacks, H 5.9e7 to
    7.1e9): the top contact touched closing at 1.6e-11, under the stall test's speed (1e-8 of
    the run's speed scale, which grows with H), so it was left out of the series for a span in
    which its force, bounded by the run's energy, moved nothing: 8e-13, below the clock's
    spacing at t = 24 051 (3.6e-11), and the run FAILED. It now goes in the series, and the
    energy never rises (measured: 6.5e-16 at most, rounding; the DOP853 method, on the two
    other stacks of the trial, agrees on h1 to 6e-12 and 1e-10; on this one it ran out of
    steps)."""
    ratios = [0.030506196958902273, 25.500119433683494, 17.318574810630352]
    ratios += [0.0028774492042644346, 0.04495568723177213, 0.004532621069393312]
    stack = (ratios, 0.14192169110898717, 0.0)
    height = 289217751.7131004
    first = simulate_stack(*stack, force="hertz", height=height, throw=False)
    assert first.status is Status.DONE
    sampled = simulate_stack(*stack, force="hertz", height=height, t_eval=_times(first))
    energy = _energy(sampled)
    assert np.diff(energy).max() <= 1e-14 * energy[0]
    assert energy[-1] < 0.1 * energy[0]
