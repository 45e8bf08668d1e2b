"""The two-ball kernel: the model advanced phase by phase in closed form (docs/model.md, "Bodies,
coordinates, forces").

Between switches the equations are linear with constant coefficients, so each phase has a
closed-form solution:

- free flight (no contact): both heights are parabolas;
- floor contact only: the lower ball is a damped oscillator about X1 = -1, the upper ball a
  parabola;
- ball contact only: the centre of mass is a parabola, the overlap X2 - X1 a damped oscillator;
- both contacts: a two-degree-of-freedom damped system, split by a real similarity into two
  decoupled 2x2 blocks (its two modes), each advanced like a damped oscillator.

The state handed from phase to phase is (X1, eta, X1', eta') with eta = X2 - X1 the overlap
(:func:`state_at`), and each phase adds the state's change, formed to its own rounding, to the
state. A contact depends on its overlap alone, which stays ~0.01 in a collision while the
heights are ~100 deep in the floor; carried as two absolute heights it would be rounded to
their ulp at every switch. A closing contact starts at zero overlap: the root is taken as
exact rather than the rounding of its terms. docs/accuracy.md, "Many-contact drops", says what
each of these choices gained.

Every oscillator, scalar or block, is written in a form that is exact across the damping branch
switch (under-, critically and overdamped) without cancellation, so modes that are close to
defective (eps near exp(-2)) cost no accuracy. The two eigenvalue pairs of the both-contact
phase are grouped so that the two closest eigenvalues share a block, and a complex pair's block
is standardised (equal diagonal entries), so that its frequency is not the small difference of
large products.

Switching times (a contact switching on or off, an apex of the upper ball) are the first roots of
the switching functions F(t) of docs/model.md, "Bodies, coordinates, forces": for an inactive
contact
F = max(eta, g), which must become negative for the contact to push; for an active contact
F = -g, which reaches zero when the force does.

Why no contact can be missed. Each step starts from a point where F > -tol and moves by the
largest h for which the parabola F + F' h - M h^2 / 2 stays above -tol, where M is a proven
bound on |F''| over the rest of the phase. The bound comes from energies that cannot grow: F''
is a constant (from the parabolas) plus a linear form in the state of each damped oscillator of
the phase, and each oscillator u'' + 2 b u' + w^2 u = 0 (b >= 0) has E = (u'^2 + w^2 u^2)/2
non-increasing, so |F''| <= c0 + c1 sqrt(2 E_1) + c2 sqrt(2 E_2) with constants worked out once
per drop (Cauchy-Schwarz). Bounding each mode on its own keeps the bound tight when the masses
differ by orders of magnitude. Between steps F is therefore certified above -tol: a root can
only be approached, never stepped over, however brief the contact or however tangent the touch.
Near a simple root the steps converge quadratically (the parabola is a second-order model).
``tol`` is a few units of rounding in the state (16 ulp of the largest terms of the closed form,
times the condition of the mode split in the both-contact phase); an overlap shallower than that
is below what double precision can represent and is the only thing that can go unnoticed.

One switch needs no steps: with one contact active, that contact's overlap is a damped
oscillator of its own (the floor's about its static compression, the balls' about touching),
so the time its force ends is a root of a damped sinusoid (or two exponentials) against a
constant, found in closed form: the force is monotone between the zeros of its rate, which are
known exactly, so the root is bracketed in the first rising stretch and found to rounding
(:func:`_release_time`). It bounds the phase like the apex does; only the other contact is
stepped. The floor contacts of a bounce sequence take two state evaluations instead of eight.

The upper ball at rest on the lower one (both contacts active for ever) is also proven rather
than guessed: once the energy of the deviation from the static equilibrium is too small for
either contact force to reach zero, no switch can ever happen again.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from twoball.jit import njit
from twoball.kernels.closed_forms import (
    _block_coefficient,
    _companion,
    _companion_row,
    _decay_pair,
    _decay_triple,
    _oscillator,
    _oscillator_bound,
    _overdamped_bound,
    _overdamped_rates,
    _release_time,
    _split_modes,
)
from twoball.kernels.codes import (
    EVENT_BALL,
    EVENT_FLOOR,
    EVENT_REST,
    EVENT_STEPS,
    EVENT_STUCK,
    MAX_STEPS_PER_PHASE,
    ROUNDING,
)

# Phase kinds: bit 0 floor contact active, bit 1 ball contact active.
FREE, FLOOR, BALL, BOTH = 0, 1, 2, 3

# _fall_deviation sums its series while tau (1 + 2 b) is at most this (terms shrink by ~4 each)
FALL_SERIES_REACH = 0.25
FALL_SERIES_TERMS = 40
FALL_SERIES_STOP = 2.0**-56  # a bound on the next term, relative to the sum so far
FALL_UNDERDAMPED = 0.01  # 1 - b^2 above which a long floor phase uses the oscillating form
SMALLEST_NORMAL = 2.2250738585072014e-308  # below it a double keeps fewer digits, then none

# Layout of the per-drop parameter vector passed to the kernel.
P_MU, P_Z01, P_Z12, P_W2, P_F1, P_F2, P_NOISE = range(7)


class Prepared(NamedTuple):
    """What the kernel needs for one drop (:func:`prepare`, arrays; :func:`constants`, the same
    fields as nested tuples of floats).

    c0[kind, contact, part] + c1[...] sqrt(2 E_1) + c2[...] sqrt(2 E_2) bounds |F''| (part 0 is
    eta, part 1 is g); rest[contact, block] bounds |g - g_rest| in the both-contact phase; x,
    blocks and companions describe its two modes; rates[block] are the decay rates of a strongly
    overdamped block (zeros otherwise) and mode_rows[contact, part, block] each functional's
    coefficients on the block's (u, u'), for :func:`_overdamped_bound`.
    """

    params: np.ndarray  # (7,) laid out as P_MU, P_Z01, ...
    c0: np.ndarray  # (4, 2, 2)
    c1: np.ndarray
    c2: np.ndarray
    rest: np.ndarray  # (2, 2)
    x: np.ndarray  # (4, 4) the both-contact phase's mode split
    x_inv: np.ndarray
    blocks: np.ndarray  # (2, 2, 2)
    companions: np.ndarray  # (2, 2, 2)
    y_rest: np.ndarray  # (4,) the both-contact phase's static rest
    rates: np.ndarray  # (2, 2)
    mode_rows: np.ndarray  # (2, 2, 2, 2)


@njit
def prepare(mu, z01, z12):
    """What the kernel needs for one drop (a :class:`Prepared`), passed on whole to :func:`run`
    as ``prepared``."""
    w2 = (1.0 + mu) / mu
    nu2 = mu / (1.0 + mu)
    b12, om12 = z12 * w2, math.sqrt(w2)
    c0 = np.zeros((4, 2, 2))
    c1 = np.zeros((4, 2, 2))
    c2 = np.zeros((4, 2, 2))
    c0[FREE, 0, 0] = c0[FREE, 0, 1] = 1.0  # x1'' = -1 and (x1 + 2 z01 v1)'' = -1
    c0[FLOOR, 1, 0] = c0[FLOOR, 1, 1] = 1.0  # the upper ball's parabola
    c1[FLOOR, 0, 0] = _oscillator_bound(1.0, 0.0, z01, 1.0)
    c1[FLOOR, 0, 1] = _oscillator_bound(1.0, 2 * z01, z01, 1.0)
    c1[FLOOR, 1, 0] = _oscillator_bound(-1.0, 0.0, z01, 1.0)
    c1[FLOOR, 1, 1] = _oscillator_bound(-1.0, -2 * z12, z01, 1.0)
    c0[BALL, 0, 0] = c0[BALL, 0, 1] = 1.0  # the centre of mass's parabola
    c1[BALL, 0, 0] = _oscillator_bound(-nu2, 0.0, b12, om12)
    c1[BALL, 0, 1] = _oscillator_bound(-nu2, -2 * z01 * nu2, b12, om12)
    c1[BALL, 1, 0] = _oscillator_bound(1.0, 0.0, b12, om12)
    c1[BALL, 1, 1] = _oscillator_bound(1.0, 2 * z12, b12, om12)
    # both contacts: y' = A (y - y_rest) for y = (X1, eta, X1', eta'), from M q'' = -C q' - K q
    # (docs/model.md, "Bodies, coordinates, forces") with eta = X2 - X1; written in these
    # coordinates directly, so that the split below resolves eta's small share of each mode
    a = np.zeros((4, 4))
    a[0, 2] = a[1, 3] = 1.0
    a[2, 0], a[2, 1], a[2, 2], a[2, 3] = -1.0, 1.0, -2.0 * z01, 2.0 * z12
    a[3, 0], a[3, 1], a[3, 2], a[3, 3] = 1.0, -w2, 2.0 * z01, -2.0 * z12 * w2
    x, x_inv, blocks = _split_modes(a)
    companions = np.empty((2, 2, 2))
    for block in range(2):
        companions[block] = _companion(blocks[block])
    functionals = np.zeros((2, 2, 4))
    functionals[0, 0, 0] = functionals[0, 1, 0] = 1.0  # X1, X1 + 2 z01 X1'
    functionals[0, 1, 2] = 2.0 * z01
    functionals[1, 0, 1] = functionals[1, 1, 1] = 1.0  # eta, eta + 2 z12 eta'
    functionals[1, 1, 3] = 2.0 * z12
    rest = np.zeros((2, 2))
    rates = np.zeros((2, 2))
    for block in range(2):
        rates[block] = _overdamped_rates(blocks[block])
    mode_rows = np.zeros((2, 2, 2, 2))
    for contact in range(2):
        for part in range(2):
            row = functionals[contact, part] @ x
            c1[BOTH, contact, part] = _block_coefficient(row[0:2], blocks[0], companions[0], 2)
            c2[BOTH, contact, part] = _block_coefficient(row[2:4], blocks[1], companions[1], 2)
            mode_rows[contact, part, 0] = _companion_row(row[0:2], companions[0])
            mode_rows[contact, part, 1] = _companion_row(row[2:4], companions[1])
        row = functionals[contact, 1] @ x
        rest[contact, 0] = _block_coefficient(row[0:2], blocks[0], companions[0], 0)
        rest[contact, 1] = _block_coefficient(row[2:4], blocks[1], companions[1], 0)
    params = np.empty(7)
    params[P_MU], params[P_Z01], params[P_Z12], params[P_W2] = mu, z01, z12, w2
    params[P_F1] = 1.0 + mu  # -g01 at rest: the floor carries both weights
    params[P_F2] = mu  # -g12 at rest: the lower ball carries the upper one
    # rounding growth of the both-contact state through x and x^-1 (1-norm condition)
    params[P_NOISE] = np.abs(x).sum(axis=0).max() * np.abs(x_inv).sum(axis=0).max()
    y_rest = np.array([-(1.0 + mu), -mu, 0.0, 0.0])  # X1 = -(1 + mu), X2 = -(1 + 2 mu)
    return Prepared(
        params=params,
        c0=c0,
        c1=c1,
        c2=c2,
        rest=rest,
        x=x,
        x_inv=x_inv,
        blocks=blocks,
        companions=companions,
        y_rest=y_rest,
        rates=rates,
        mode_rows=mode_rows,
    )


@njit
def _pair(a):
    """The first two entries of a (an array's row, as a tuple)."""
    return a[0], a[1]


@njit
def _square(m):
    """A 2x2 array as a nested tuple."""
    return _pair(m[0]), _pair(m[1])


@njit
def _quad(a):
    """The first four entries of a (an array's row, as a tuple)."""
    return a[0], a[1], a[2], a[3]


@njit
def constants(prepared):
    """What :func:`prepare` returned, as a :class:`Prepared` of nested tuples of floats (indexed
    alike).

    :func:`run` steps with these: an array handed to a compiled function costs an atomic
    reference-count increment and decrement per call, which in the stepping loop took about
    half the kernel's time; tuples of floats cost nothing to pass.
    """
    params, c0, c1, c2 = prepared.params, prepared.c0, prepared.c1, prepared.c2
    x, x_inv, mode_rows = prepared.x, prepared.x_inv, prepared.mode_rows
    blocks, companions = prepared.blocks, prepared.companions
    return Prepared(
        params=(params[0], params[1], params[2], params[3], params[4], params[5], params[6]),
        c0=(_square(c0[0]), _square(c0[1]), _square(c0[2]), _square(c0[3])),
        c1=(_square(c1[0]), _square(c1[1]), _square(c1[2]), _square(c1[3])),
        c2=(_square(c2[0]), _square(c2[1]), _square(c2[2]), _square(c2[3])),
        rest=_square(prepared.rest),
        x=(_quad(x[0]), _quad(x[1]), _quad(x[2]), _quad(x[3])),
        x_inv=(_quad(x_inv[0]), _quad(x_inv[1]), _quad(x_inv[2]), _quad(x_inv[3])),
        blocks=(_square(blocks[0]), _square(blocks[1])),
        companions=(_square(companions[0]), _square(companions[1])),
        y_rest=_quad(prepared.y_rest),
        rates=_square(prepared.rates),
        mode_rows=(
            (_square(mode_rows[0, 0]), _square(mode_rows[0, 1])),
            (_square(mode_rows[1, 0]), _square(mode_rows[1, 1])),
        ),
    )


@njit
def _row4(m, i, a, b, c, d):
    """Row i of a 4x4 matrix (array or nested tuple) times (a, b, c, d), without allocating."""
    return m[i][0] * a + m[i][1] * b + m[i][2] * c + m[i][3] * d


@njit
def _rest_size(y_rest):
    """|X1| + |X2| at the both-contact phase's static rest (``y_rest`` holds X1 and eta): the
    offset its closed form works about, whose rounding the state carries."""
    return abs(y_rest[0]) + abs(y_rest[0] + y_rest[1])


@njit
def _modes(x1, eta, v1, deta, x_inv, y_rest):
    """Mode coordinates z = X^-1 (y - y_rest) of a both-contact state y = (x1, eta, v1, eta')."""
    d1, d2 = x1 - y_rest[0], eta - y_rest[1]
    return (
        _row4(x_inv, 0, d1, d2, v1, deta),
        _row4(x_inv, 1, d1, d2, v1, deta),
        _row4(x_inv, 2, d1, d2, v1, deta),
        _row4(x_inv, 3, d1, d2, v1, deta),
    )


@njit
def _block_flow(b, z0, z1, tau):
    """exp(B tau) z and B exp(B tau) z for a 2x2 block (an array), exact on every damping
    branch; see :func:`_flow`."""
    return _flow(b[0, 0], b[0, 1], b[1, 0], b[1, 1], z0, z1, tau)


@njit
def _flow(b00, b01, b10, b11, z0, z1, tau):
    """exp(B tau) z and B exp(B tau) z for the 2x2 block B = [[b00, b01], [b10, b11]]:
    exp(B tau) = cos_part I + sin_part (B - tr(B)/2 I) with the oscillator's decay pair."""
    half_trace = 0.5 * (b00 + b11)
    cos_part, sin_part = _decay_pair(-half_trace, b00 * b11 - b01 * b10, tau)
    n0 = cos_part * z0 + sin_part * ((b00 - half_trace) * z0 + b01 * z1)
    n1 = cos_part * z1 + sin_part * (b10 * z0 + (b11 - half_trace) * z1)
    return n0, n1, b00 * n0 + b01 * n1, b10 * n0 + b11 * n1


@njit
def _block_change(block, z0, z1, tau):
    """For a 2x2 block (array or nested tuple): exp(B tau) z, its change (exp(B tau) - I) z,
    each to its own rounding (:func:`_decay_triple`), and B exp(B tau) z; see :func:`_flow`."""
    b00, b01, b10, b11 = block[0][0], block[0][1], block[1][0], block[1][1]
    half_trace = 0.5 * (b00 + b11)
    cos_part, cos_less_one, sin_part = _decay_triple(-half_trace, b00 * b11 - b01 * b10, tau)
    p0 = sin_part * ((b00 - half_trace) * z0 + b01 * z1)
    p1 = sin_part * (b10 * z0 + (b11 - half_trace) * z1)
    n0, n1 = cos_part * z0 + p0, cos_part * z1 + p1
    return (
        n0,
        n1,
        cos_less_one * z0 + p0,
        cos_less_one * z1 + p1,
        b00 * n0 + b01 * n1,
        b10 * n0 + b11 * n1,
    )


@njit
def _from_modes(row, start, rest, n0, n1, n2, n3, d0, d1, d2, d3):
    """One coordinate of a both-contact state from its modes: the start plus the change, or the
    static rest plus the modes' values, whichever sums smaller terms (the change after a short
    phase; the values once the modes have decayed, as in a strongly damped phase)."""
    change = row[0] * d0 + row[1] * d1 + row[2] * d2 + row[3] * d3
    change_size = abs(row[0] * d0) + abs(row[1] * d1) + abs(row[2] * d2) + abs(row[3] * d3)
    value_size = abs(rest) + abs(row[0] * n0) + abs(row[1] * n1) + abs(row[2] * n2)
    value_size += abs(row[3] * n3)
    if change_size <= value_size:
        return start + change
    return rest + (row[0] * n0 + row[1] * n1 + row[2] * n2 + row[3] * n3)


@njit
def _sine_excess(x):
    """sin(x) - x without cancellation (its series below |x| = 1)."""
    if abs(x) >= 1.0:
        return math.sin(x) - x
    square = x * x
    term = -x * square / 6.0
    total = term
    for k in range(2, 12):
        term *= -square / ((2 * k) * (2 * k + 1))
        total += term
    return total


@njit
def _fall_deviation(u0, v0, b, tau):
    """D = u(tau) - (u0 + v0 tau - tau^2/2) and D' for u'' + 2 b u' + u = 0: how far the floor
    has pushed the lower ball off its free fall, without the cancellation of subtracting two
    nearly equal heights.

    The upper ball falls freely meanwhile, so the overlap moves by eta' tau minus this. In a
    collision the lower ball sits ~100 deep in the floor at H = 1e4 while the overlap is ~0.01;
    when the upper ball comes down on a lower ball already in the floor, the overlap closes from
    ~50 to 0 by the difference of D (~50) and eta' tau. So D is formed to its own rounding:
    short phases sum the Taylor series (u^(k+2) = -2 b u^(k+1) - u^(k)); longer underdamped
    ones write D = (C - 1) u0 + (S - tau) v0 + b S u0 + tau^2/2 with the decay pair (C, S) of
    :func:`_decay_pair` and C - 1, S - tau formed without cancellation; the rest (overdamped or
    near critical, and long) subtract.
    """
    growth = 1.0 + 2.0 * b
    if tau * growth > FALL_SERIES_REACH:
        d = 1.0 - b * b
        if d < FALL_UNDERDAMPED:
            u, v, _ = _oscillator(u0, v0, b, 1.0, tau)
            return (u - u0) - tau * (v0 - 0.5 * tau), (v - v0) + tau
        om = math.sqrt(d)
        angle = om * tau
        decay_less_one = math.expm1(-b * tau)
        half = math.sin(0.5 * angle)
        cos_less_one = decay_less_one * math.cos(angle) - 2.0 * half * half  # C - 1
        sin_part = (1.0 + decay_less_one) * math.sin(angle) / om  # S
        sin_less_tau = (1.0 + decay_less_one) * _sine_excess(angle) / om + tau * decay_less_one
        deviation = cos_less_one * u0 + b * sin_part * u0 + sin_less_tau * v0 + 0.5 * tau * tau
        rate = cos_less_one * v0 - sin_part * (u0 + b * v0) + tau
        return deviation, rate
    before, now = v0, -2.0 * b * v0 - u0  # u', u''
    power, lower = 0.5 * tau * tau, tau  # tau^k/k!, tau^(k-1)/(k-1)! for k = 2
    deviation, rate = (now + 1.0) * power, (now + 1.0) * lower
    for k in range(3, FALL_SERIES_TERMS):
        before, now = now, -2.0 * b * now - before
        lower = power
        power = power * tau / k
        deviation += now * power
        rate += now * lower
        reach = (abs(now) + abs(before)) * growth
        if reach * power <= FALL_SERIES_STOP * abs(deviation) and (
            reach * lower <= FALL_SERIES_STOP * abs(rate)
        ):
            break
    return deviation, rate


@njit
def state_at(kind, tau, x1, eta, v1, deta, params, x, x_inv, blocks, y_rest):
    """Exact state (x1, eta, v1, eta', a1, eta'') a time tau into a phase of the given kind.

    The state is carried in relative coordinates: the lower ball's height and velocity, and the
    overlap eta = X2 - X1 and its rate. A ball contact depends on eta alone, which stays small
    (~0.01) in a collision while both heights are ~100 deep in the floor; carried as the
    difference of two absolute heights, it would be rounded to their ulp at every switch, the
    largest loss of accuracy on drops with many contacts (docs/accuracy.md). Rounding of x1 and
    v1 moves both balls together, which the contacts barely feel.
    """
    mu, z01, z12, w2 = params[P_MU], params[P_Z01], params[P_Z12], params[P_W2]
    if kind == FREE:
        # gravity drops out of the relative motion: eta is linear in time
        return x1 + tau * (v1 - 0.5 * tau), eta + tau * deta, v1 - tau, deta, -1.0, 0.0
    # Every kind adds the state's change over tau to the state, the change formed to its own
    # rounding: a short phase then rounds each coordinate once, by its ulp, rather than by the
    # few ulps of a closed form of the state's whole size (h1 and h2 follow the release speed,
    # which many contacts would otherwise blur).
    if kind == FLOOR:
        pushed, pushed_rate = _fall_deviation(x1 + 1.0, v1, z01, tau)
        if tau * (1.0 + 2.0 * z01) > FALL_SERIES_REACH:
            # a long phase: the push undoes much of the fall (a ball settling in the floor
            # while the other flies), so the lower ball's own closed form is the accurate one
            u, v1_t, a1 = _oscillator(x1 + 1.0, v1, z01, 1.0, tau)
            x1_t = u - 1.0
        else:
            x1_t = x1 + (tau * (v1 - 0.5 * tau) + pushed)
            v1_t = v1 + (pushed_rate - tau)
            a1 = -2.0 * z01 * v1_t - (x1_t + 1.0)
        return x1_t, eta + (tau * deta - pushed), v1_t, deta - pushed_rate, a1, -1.0 - a1
    if kind == BALL:
        share1 = mu / (1.0 + mu)
        eta_t, deta_t, ddeta = _oscillator(eta, deta, z12 * w2, w2, tau)
        vc = v1 + share1 * deta
        return (
            x1 + (share1 * (eta - eta_t) + tau * (vc - 0.5 * tau)),
            eta_t,
            v1 + (share1 * (deta - deta_t) - tau),
            deta_t,
            -1.0 - share1 * ddeta,
            ddeta,
        )
    z0, z1, z2, z3 = _modes(x1, eta, v1, deta, x_inv, y_rest)
    n0, n1, d0, d1, r0, r1 = _block_change(blocks[0], z0, z1, tau)
    n2, n3, d2, d3, r2, r3 = _block_change(blocks[1], z2, z3, tau)
    return (
        _from_modes(x[0], x1, y_rest[0], n0, n1, n2, n3, d0, d1, d2, d3),
        _from_modes(x[1], eta, y_rest[1], n0, n1, n2, n3, d0, d1, d2, d3),
        _from_modes(x[2], v1, 0.0, n0, n1, n2, n3, d0, d1, d2, d3),
        _from_modes(x[3], deta, 0.0, n0, n1, n2, n3, d0, d1, d2, d3),
        _row4(x, 2, r0, r1, r2, r3),
        _row4(x, 3, r0, r1, r2, r3),
    )


@njit
def _safe_step(f, fp, bound):
    """Largest h with f + fp h - bound h^2/2 > 0 on [0, h), for f > 0."""
    if bound <= 0.0:
        return f / (-fp) if fp < 0.0 else np.inf
    room = 2.0 * bound * f
    if room < SMALLEST_NORMAL:
        # The product underflowed: a cluster whose motion has decayed into subnormal numbers
        # (a stack resting for a thousand time units) bounds its curvature by ~1e-320, and
        # 2 bound f rounded to zero gave h = 0 with fp = 0, a step of nothing (a run STUCK).
        # Its square root, formed from the factors' roots, keeps its digits.
        root = math.hypot(fp, math.sqrt(2.0 * bound) * math.sqrt(f))
    else:
        root = math.sqrt(fp * fp + room)
    if fp >= 0.0:
        return (fp + root) / bound
    return 2.0 * f / (root - fp)


@njit
def _curvature_bound(kind, contact, part, c0, c1, c2, roots, rates, mode_rows, block_states):
    """Bound on |F''| of one part (0: eta, 1: g) of a contact's switching function for the rest
    of the phase: c0 + c1 sqrt(2 E_1) + c2 sqrt(2 E_2), where a strongly overdamped mode of the
    both-contact phase takes the tighter of its energy bound and its two-exponential bound."""
    first = c1[kind][contact][part] * roots[0]
    second = c2[kind][contact][part] * roots[1]
    if kind == BOTH:
        if rates[0][1] > 0.0:
            tight = _overdamped_bound(
                rates[0], mode_rows[contact][part][0], block_states[0], block_states[1], 2
            )
            first = min(first, tight)
        if rates[1][1] > 0.0:
            tight = _overdamped_bound(
                rates[1], mode_rows[contact][part][1], block_states[2], block_states[3], 2
            )
            second = min(second, tight)
    return c0[kind][contact][part] + first + second


@njit
def _switching(
    contact, active, x1, eta, v1, deta, a1, ddeta, params, bound_eta, bound_g, tol_state, clock
):
    """One contact's switching function: (F, F', tol, step certified above -tol); see
    :func:`contact_switch`."""
    if contact == 0:
        return contact_switch(
            active, x1, v1, a1, params[P_Z01], bound_eta, bound_g, tol_state, clock
        )
    return contact_switch(
        active, eta, deta, ddeta, params[P_Z12], bound_eta, bound_g, tol_state, clock
    )


@njit
def contact_switch(active, eta, deta, ddeta, zeta, bound_eta, bound_g, tol_state, clock):
    """A contact's switching function from its overlap eta and two derivatives:
    (F, F', tol, step certified above -tol).

    bound_eta and bound_g bound |eta''| and |g''| for the rest of the phase; tol is the rounding
    in F: that of the state, plus |F'| times the rounding of the clock. Shared with the N-ball
    solver (twoball.kernels.stack).
    """
    g = eta + 2.0 * zeta * deta
    dg = deta + 2.0 * zeta * ddeta
    tol_g = tol_state + ROUNDING * abs(dg) * clock
    if active:
        value, rate = -g, -dg
        step = _safe_step(value + tol_g, rate, bound_g) if value > -tol_g else 0.0
        return value, rate, tol_g, step
    tol_eta = tol_state + ROUNDING * abs(deta) * clock
    if eta >= g:
        value, rate, tol = eta, deta, tol_eta
    else:
        value, rate, tol = g, dg, tol_g
    step = 0.0
    if eta > -tol_eta:
        step = _safe_step(eta + tol_eta, deta, bound_eta)
    if g > -tol_g:
        step = max(step, _safe_step(g + tol_g, dg, bound_g))
    return value, rate, tol, step


@njit
def _mode_energy_root(block, u, du):
    """sqrt(2 E) of a mode's oscillator energy E = (u'^2 + det(B) u^2)/2."""
    det = block[0][0] * block[1][1] - block[0][1] * block[1][0]
    return math.sqrt(du * du + det * u * u)


@njit
def _energy_roots(kind, v1, deta, a1, ddeta, params, blocks, block_states):
    """sqrt(2 E) of each oscillator of the phase (of w = y' for one contact; for both contacts,
    E = (u'^2 + det(B) u^2)/2 of each mode from its (u, u') in ``block_states``); each is
    non-increasing within the phase."""
    if kind == FLOOR:
        return math.sqrt(a1 * a1 + v1 * v1), 0.0
    if kind == BALL:
        return math.sqrt(ddeta * ddeta + params[P_W2] * deta * deta), 0.0
    if kind == BOTH:
        return (
            _mode_energy_root(blocks[0], block_states[0], block_states[1]),
            _mode_energy_root(blocks[1], block_states[2], block_states[3]),
        )
    return 0.0, 0.0


@njit
def _block_states(x1, eta, v1, deta, x_inv, companions, y_rest):
    """(u, u') of each mode's oscillator in the both-contact phase: (u_1, u_1', u_2, u_2')."""
    z0, z1, z2, z3 = _modes(x1, eta, v1, deta, x_inv, y_rest)
    return (
        companions[0][0][0] * z0 + companions[0][0][1] * z1,
        companions[0][1][0] * z0 + companions[0][1][1] * z1,
        companions[1][0][0] * z2 + companions[1][0][1] * z3,
        companions[1][1][0] * z2 + companions[1][1][1] * z3,
    )


@njit
def _at_rest(roots, params, rest, rates, mode_rows, block_states, tol):
    """True when neither contact of the both-contact phase can ever switch off again: the mode
    energies (or, for a strongly overdamped mode, its two exponentials) are too small for -g to
    fall from its value at rest to zero."""
    for contact in range(2):
        margin = params[P_F1] if contact == 0 else params[P_F2]
        for block in range(2):
            excursion = rest[contact][block] * roots[block]
            if rates[block][1] > 0.0:
                tight = _overdamped_bound(
                    rates[block],
                    mode_rows[contact][1][block],
                    block_states[2 * block],
                    block_states[2 * block + 1],
                    0,
                )
                excursion = min(excursion, tight)
            margin -= excursion
        if not margin > tol:
            return False
    return True


@njit
def advance_phase(
    kind, t, x1, eta, v1, deta, horizon, horizon_event, prepared, entered_by=-1, carried=0.0
):
    """Advance one phase, started at time t from the state (x1, eta, v1, eta') of
    :func:`state_at`, to its first event.

    Returns (event, tau, x1, eta, v1, eta', steps, solves) with tau the time into the phase, steps
    the certified steps taken and solves the closed-form release times solved for. horizon is a
    known event time (apex or end of the run) with its event code; prepared is what :func:`prepare`
    returned. With one contact active, that contact's oscillator moves on its own, so the time
    its force ends is found in closed form (:func:`_release_time`) and becomes the horizon; only
    the other contact is stepped.
    """
    params, c0, c1, c2 = prepared.params, prepared.c0, prepared.c1, prepared.c2
    rest, x, x_inv, blocks = prepared.rest, prepared.x, prepared.x_inv, prepared.blocks
    companions, y_rest = prepared.companions, prepared.y_rest
    rates, mode_rows = prepared.rates, prepared.mode_rows
    z01, z12, w2_ball = params[P_Z01], params[P_Z12], params[P_W2]
    noise = params[P_NOISE] if kind == BOTH else 1.0
    # the tolerances keep their scale of absolute heights and speeds: they bound the rounding of
    # the switching functions' absolute parts, whatever coordinates carry the state
    size = 1.0 + abs(x1) + abs(x1 + eta)
    # Without the ball contact the lower ball moves on its own, so the floor contact's rounding
    # is that of the lower ball alone (an upper ball far above must not blunt it).
    lower_alone = (kind & 2) == 0
    size_lower, speed_lower = 1.0 + abs(x1), abs(v1)
    if kind == BOTH:
        # the closed form works about the static rest (heights ~ -mu for a heavy upper ball):
        # its rounding scales with that offset too
        size += _rest_size(y_rest)
    speed = abs(v1) + abs(v1 + deta)
    floor_on = (kind & 1) != 0
    ball_on = (kind & 2) != 0
    own = EVENT_FLOOR if kind == FLOOR else EVENT_BALL if kind == BALL else -1
    tau = 0.0
    last_step = 0.0
    steps = 0
    solves = 0
    for _ in range(MAX_STEPS_PER_PHASE):
        steps += 1
        y1, y2, w1, w2, a1, a2 = state_at(
            kind, tau, x1, eta, v1, deta, params, x, x_inv, blocks, y_rest
        )
        block_states = (0.0, 0.0, 0.0, 0.0)
        if kind == BOTH:
            block_states = _block_states(y1, y2, w1, w2, x_inv, companions, y_rest)
        roots = _energy_roots(kind, w1, w2, a1, a2, params, blocks, block_states)
        # rounding of the closed form at tau: its largest terms are x0, v0 tau and tau^2/2
        tol_state = ROUNDING * noise * (size + speed * (1.0 + tau) + tau * tau) + carried
        tol_lower = tol_state
        if lower_alone:
            tol_lower = ROUNDING * (size_lower + speed_lower * (1.0 + tau) + tau * tau) + carried
        clock = 1.0 + t + tau
        step = horizon - tau
        event = -1
        best = np.inf
        for contact in range(2):
            if contact == own and tau > 0.0:
                continue  # its end is the horizon
            active = floor_on if contact == 0 else ball_on
            bound_eta = _curvature_bound(
                kind, contact, 0, c0, c1, c2, roots, rates, mode_rows, block_states
            )
            bound_g = _curvature_bound(
                kind, contact, 1, c0, c1, c2, roots, rates, mode_rows, block_states
            )
            value, rate, tol, h = _switching(
                contact,
                active,
                y1,
                y2,
                w1,
                w2,
                a1,
                a2,
                params,
                bound_eta,
                bound_g,
                tol_lower if contact == 0 else tol_state,
                clock,
            )
            # The contact whose switch began this phase starts it at F = 0 with a rate of the
            # right sign; only at a tangency (F, F' and F'' all zero, as when both balls touch
            # at release and meet an elastic floor together) can rounding give the rate the
            # wrong sign, which would switch it straight back, for ever. So at the phase's
            # first point it switches back only from clearly past its root.
            fresh = contact == entered_by and tau == 0.0
            if value <= -tol or (value <= tol and rate < 0.0 and not fresh):
                # At a root to rounding: one Newton correction, never past the certified step
                # nor back before the last certified point. The certified steps aim at F = -tol,
                # so without the backward correction every switch is placed up to tol/|F'| late,
                # a bias that adds up over many contacts (docs/accuracy.md).
                shift = 0.0
                if rate < 0.0:
                    shift = min(max(value / -rate, -last_step), h)
                if contact == entered_by and tau + shift <= 0.0:
                    shift = 0.0  # not back to where it switched (see fresh above)
                if tau + shift < best:
                    best, event = tau + shift, contact
            elif contact == own:
                # the force ends at -tol once it is within tol of zero just after switching on
                level = tol if fresh and value <= tol else 0.0
                solves += 1
                if kind == FLOOR:
                    release = _release_time(x1 + 1.0, v1, z01, 1.0, z01, 1.0 + level, horizon)
                else:
                    release = _release_time(eta, deta, z12 * w2_ball, w2_ball, z12, level, horizon)
                if release < horizon:
                    horizon, horizon_event = release, own
                    step = min(step, horizon - tau)
            else:
                step = min(step, h)
        if event >= 0:
            if best != tau:  # else the state is the one just computed
                y1, y2, w1, w2, _, _ = state_at(
                    kind, best, x1, eta, v1, deta, params, x, x_inv, blocks, y_rest
                )
            return event, best, y1, y2, w1, w2, steps, solves
        if kind == BOTH and _at_rest(
            roots, params, rest, rates, mode_rows, block_states, tol_state
        ):
            return EVENT_REST, tau, y1, y2, w1, w2, steps, solves
        if tau + step >= horizon:
            y1, y2, w1, w2, _, _ = state_at(
                kind, horizon, x1, eta, v1, deta, params, x, x_inv, blocks, y_rest
            )
            return horizon_event, horizon, y1, y2, w1, w2, steps, solves
        if not 0.0 < step < np.inf:
            return EVENT_STUCK, tau, x1, eta, v1, deta, steps, solves
        tau += step
        last_step = step
    return EVENT_STEPS, tau, x1, eta, v1, deta, steps, solves
