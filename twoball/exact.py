"""The exact solver: the model advanced phase by phase in closed form (docs/model.md, "Bodies,
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

from twoball.errors import ParameterError, Status
from twoball.jit import njit
from twoball.kernels.codes import (
    EVENT_APEX,
    EVENT_BALL,
    EVENT_FLOOR,
    EVENT_REST,
    EVENT_STEPS,
    EVENT_STUCK,
    EVENT_TIME,
    MAX_PHASES,
    MAX_STEPS_PER_PHASE,
    ROUNDING,
    STATUS_DONE,
    STATUS_PHASES,
    STATUS_REST,
    STATUS_STUCK,
)
from twoball.model import Drop
from twoball.observables import Outcome

# Phase kinds: bit 0 floor contact active, bit 1 ball contact active.
FREE, FLOOR, BALL, BOTH = 0, 1, 2, 3

MAX_ROOT_ITERATIONS = 100  # of a bracketed Halley search (it converges in about three)
SUBSPACE_SWEEPS = 4  # refinement sweeps of the both-contact mode split (see _split_modes)
OVERDAMPED_GAP = 0.1  # rates this far apart (relative) split a block into two exponentials
OVERDAMPED_SAFETY = 1.0 + 1e-9  # covers the rounding of that split (relative ~ulp / gap)
# _fall_deviation sums its series while tau (1 + 2 b) is at most this (terms shrink by ~4 each)
FALL_SERIES_REACH = 0.25
FALL_SERIES_TERMS = 40
FALL_SERIES_STOP = 2.0**-56  # a bound on the next term, relative to the sum so far
FALL_UNDERDAMPED = 0.01  # 1 - b^2 above which a long floor phase uses the oscillating form

# Layout of the per-drop parameter vector passed to the kernel.
P_MU, P_Z01, P_Z12, P_W2, P_F1, P_F2, P_NOISE = range(7)


@njit
def _oscillator_bound(alpha, beta, b, omega):
    """c for s = alpha u + beta u' on u'' + 2 b u' + omega^2 u = 0: |s''| <= c sqrt(2 E_w),
    E_w the energy of w = u' (which obeys the same equation)."""
    return math.hypot(alpha - 2.0 * b * beta, omega * beta)  # Cauchy-Schwarz on the energy


@njit
def _decay_pair(b, w2, tau):
    """exp(-b tau) cos(W tau) and exp(-b tau) sin(W tau)/W with W^2 = w2 - b^2 (b >= 0, w2 > 0).

    On the overdamped branch (W imaginary) cosh and sinh appear; all three branches are written
    without cancellation, so W near 0 (critical damping) loses nothing.
    """
    d = w2 - b * b
    if d > 0.0:
        om = math.sqrt(d)
        decay = math.exp(-b * tau)
        return decay * math.cos(om * tau), decay * math.sin(om * tau) / om
    if d < 0.0:
        om = math.sqrt(-d)
        slow = math.exp(-(w2 / (b + om)) * tau)  # exp(-(b - om) tau) without cancellation
        return (
            0.5 * slow * (1.0 + math.exp(-2.0 * om * tau)),
            slow * (-math.expm1(-2.0 * om * tau)) / (2.0 * om),
        )
    decay = math.exp(-b * tau)
    return decay, tau * decay


@njit
def _decay_triple(b, w2, tau):
    """(C, C - 1, S) for the decay pair (C, S) of :func:`_decay_pair`, C - 1 formed without
    cancellation: a short phase can then move a state by its change alone (rounded to the
    change's size, not the state's), and a long one that has decayed by its final value."""
    d = w2 - b * b
    if d > 0.0:
        om = math.sqrt(d)
        angle = om * tau
        decay_less_one = math.expm1(-b * tau)
        half = math.sin(0.5 * angle)
        cosine = math.cos(angle)
        return (
            math.exp(-b * tau) * cosine,
            decay_less_one * cosine - 2.0 * half * half,
            (1.0 + decay_less_one) * math.sin(angle) / om,
        )
    if d < 0.0:
        om = math.sqrt(-d)
        slow_rate = w2 / (b + om)  # b - om without cancellation
        slow = math.exp(-slow_rate * tau)
        return (
            0.5 * slow * (1.0 + math.exp(-2.0 * om * tau)),
            0.5 * (math.expm1(-slow_rate * tau) + math.expm1(-(slow_rate + 2.0 * om) * tau)),
            slow * (-math.expm1(-2.0 * om * tau)) / (2.0 * om),
        )
    decay = math.exp(-b * tau)
    return decay, math.expm1(-b * tau), tau * decay


@njit
def _oscillator(u0, v0, b, w2, tau):
    """u, u', u'' at tau for u'' + 2 b u' + w2 u = 0 from (u0, v0), on every damping branch."""
    cos_part, sin_part = _decay_pair(b, w2, tau)
    u = cos_part * u0 + sin_part * (v0 + b * u0)
    v = cos_part * v0 - sin_part * (w2 * u0 + b * v0)
    return u, v, -2.0 * b * v - w2 * u


@njit
def _oscillator_zeros(y0, y1, b, w2):
    """The first two times t > 0 at which y = 0, for y'' + 2 b y' + w2 y = 0 from (y0, y1)
    (inf where there are fewer), on every damping branch.

    With the decay pair of :func:`_decay_pair`, y = cos_part y0 + sin_part p (p = y1 + b y0).
    Underdamped, y = exp(-b t) R cos(W t - phi): zeros pi/W apart. Otherwise at most one zero,
    where exp(-2 Om t) = 1 + x with x = 2 Om y0 / (p - Om y0), written without cancellation as
    Om goes to 0 (the critical branch's t = -y0/p).
    """
    p = y1 + b * y0
    d = w2 - b * b
    if d > 0.0:
        om = math.sqrt(d)
        theta = math.atan2(p / om, y0) - 0.5 * math.pi  # a zero, in (-3 pi/2, pi/2]
        while theta <= 0.0:
            theta += math.pi
        return theta / om, (theta + math.pi) / om
    om = math.sqrt(-d)
    denominator = p - om * y0
    if denominator == 0.0:
        return np.inf, np.inf  # y is the fast exponential alone
    ratio = y0 / denominator
    x = 2.0 * om * ratio
    if not (ratio < 0.0 and x > -1.0):
        return np.inf, np.inf
    return -ratio * (math.log1p(x) / x if x != 0.0 else 1.0), np.inf


@njit
def _release_time(u0, v0, b, w2, zeta, level, limit):
    """When an active contact's force ends, in closed form: the first t in (0, limit) at which
    q = u + 2 zeta u' rises to ``level`` for u'' + 2 b u' + w2 u = 0 from (u0, v0); inf if none.

    The contact's force is level - q (docs/model.md, "Bodies, coordinates, forces": u is the
    overlap about the static rest, level its static force), and q obeys the same equation. q is
    monotone between consecutive zeros of q' (:func:`_oscillator_zeros`), so it can rise
    through the level only in its first rising stretch: its later maxima are each smaller by
    exp(-2 pi b / W), and the other branches turn at most once. The root is bracketed there and
    found by Halley's method (q'' comes with the closed form) kept inside the bracket, so none is
    missed or approximated by steps.
    """
    q0 = u0 + 2.0 * zeta * v0
    dq0 = v0 + 2.0 * zeta * (-2.0 * b * v0 - w2 * u0)
    first, second = _oscillator_zeros(dq0, -2.0 * b * dq0 - w2 * q0, b, w2)
    low, high = (0.0, first) if dq0 >= 0.0 else (first, second)
    high = min(high, limit)
    if not (low < high < np.inf):
        return np.inf
    u, v, _ = _oscillator(u0, v0, b, w2, high)
    if u + 2.0 * zeta * v < level:
        return np.inf  # its rise stops short of the level (or the limit comes first)
    if q0 >= level:  # q falls to low from q0, so only then can it start the stretch past the level
        u, v, _ = _oscillator(u0, v0, b, w2, low)
        if u + 2.0 * zeta * v >= level:
            return low
    # start where q crosses zero in the stretch (its inflection, when undamped), else mid-way
    t = 0.5 * (low + high)
    for zero in _oscillator_zeros(q0, dq0, b, w2):
        if low < zero < high:
            t = zero
    for _ in range(MAX_ROOT_ITERATIONS):
        u, v, a = _oscillator(u0, v0, b, w2, t)
        gap = u + 2.0 * zeta * v - level
        if gap >= 0.0:
            high = t
        else:
            low = t
        slope = v + 2.0 * zeta * a
        bend = a - 2.0 * zeta * (2.0 * b * a + w2 * v)  # q'', with u''' = -2 b u'' - w2 u'
        halley = 2.0 * slope * slope - gap * bend
        following = t - 2.0 * gap * slope / halley if slope > 0.0 and halley > 0.0 else -1.0
        if not low <= following <= high:
            following = 0.5 * (low + high)
        if abs(following - t) <= ROUNDING * t:
            return following
        t = following
    return t


@njit
def _pair_polynomial(a, first, second):
    """(A - first I)(A - second I) for an eigenvalue pair closed under conjugation (real)."""
    trace = (first + second).real
    product = (first * second).real
    return a @ a - trace * a + product * np.eye(4)


@njit
def _column_basis(p):
    """An orthonormal basis (as columns) of the rank-2 column space of p, by pivoted
    Gram-Schmidt."""
    columns = np.ascontiguousarray(p.T)
    basis = np.zeros((2, 4))
    for k in range(2):
        best, norm = 0, -1.0
        for j in range(4):
            col_norm = math.sqrt(columns[j] @ columns[j])
            if col_norm > norm:
                best, norm = j, col_norm
        basis[k] = columns[best] / norm
        for j in range(4):
            columns[j] = columns[j] - (basis[k] @ columns[j]) * basis[k]
    return basis.T


@njit
def _orthonormal_pair(m):
    """An orthonormal basis of the span of the two columns of m (Gram-Schmidt, twice)."""
    first = np.ascontiguousarray(m[:, 0])
    first = first / math.sqrt(first @ first)
    second = np.ascontiguousarray(m[:, 1])
    second = second - (first @ second) * first
    second = second - (first @ second) * first
    q = np.empty((4, 2))
    q[:, 0] = first
    q[:, 1] = second / math.sqrt(second @ second)
    return q


@njit
def _split_modes(a):
    """A real X with X^-1 A X = diag(B0, B1), 2x2 blocks holding one eigenvalue pair each.

    Of the three ways to pair four eigenvalues, the admissible ones keep each pair real or
    complex-conjugate; among them the one whose pairs lie furthest apart is taken, so the two
    closest eigenvalues (a near-defective mode) share a block, where the closed form is exact.
    """
    lam = np.linalg.eigvals(a.astype(np.complex128))
    scale = np.abs(lam).max()
    pairings = ((0, 1, 2, 3), (0, 2, 1, 3), (0, 3, 1, 2))
    chosen, separation = pairings[0], -1.0
    for pairing in pairings:
        ok = True
        for k in range(2):
            first, second = lam[pairing[2 * k]], lam[pairing[2 * k + 1]]
            both_real = abs(first.imag) + abs(second.imag) <= 1e-12 * scale
            conjugate = abs(first - np.conj(second)) <= 1e-12 * scale
            ok = ok and (both_real or conjugate)
        if not ok:
            continue
        gap = np.inf
        for i in range(2):
            for j in range(2, 4):
                gap = min(gap, abs(lam[pairing[i]] - lam[pairing[j]]))
        if gap > separation:
            chosen, separation = pairing, gap
    x = np.empty((4, 4))
    # the column space of the other pair's polynomial is this pair's invariant subspace
    x[:, 0:2] = _column_basis(_pair_polynomial(a, lam[chosen[2]], lam[chosen[3]]))
    x[:, 2:4] = _column_basis(_pair_polynomial(a, lam[chosen[0]], lam[chosen[1]]))
    # The pair polynomial cancels: for small mu |A|^2 ~ 1/mu^2 while the fast pair's share is
    # ~1/mu, so its subspace is off by ~1/mu ulp and the ignored coupling blocks of X^-1 A X
    # inject ~1e-13 relative per both-contact phase, which many contacts amplify (docs/accuracy.md).
    # Subspace iteration refines both: the pair of larger modulus by A, the other by A^-1; each
    # sweep shrinks the other subspace's share by the modulus ratio (at most 1/2 here).
    low_pair, high_pair = (0, 2), (2, 0)
    smaller = max(abs(lam[chosen[0]]), abs(lam[chosen[1]]))
    larger = min(abs(lam[chosen[2]]), abs(lam[chosen[3]]))
    if smaller > larger:
        low_pair, high_pair = (2, 0), (0, 2)
        smaller = max(abs(lam[chosen[2]]), abs(lam[chosen[3]]))
        larger = min(abs(lam[chosen[0]]), abs(lam[chosen[1]]))
    if smaller < 0.5 * larger:
        a_inv = np.ascontiguousarray(np.linalg.inv(a))
        lo, hi = low_pair[0], high_pair[0]
        for _ in range(SUBSPACE_SWEEPS):
            x[:, lo : lo + 2] = _orthonormal_pair(a_inv @ np.ascontiguousarray(x[:, lo : lo + 2]))
            x[:, hi : hi + 2] = _orthonormal_pair(a @ np.ascontiguousarray(x[:, hi : hi + 2]))
    # Within each invariant plane, rotate the basis so that the block's diagonal entries are
    # equal (the standardised form of a real Schur block): its determinant is then
    # b00^2 - b01 b10 with no cancellation. An arbitrary orthonormal basis of the fast mode's
    # elongated orbit gives diagonal entries of +-300 whose products cancel to a determinant of
    # ~3000 (mu ~ 3e-4), and that frequency error, 1e-14 relative, drifts the fast mode's phase
    # contact by contact (docs/accuracy.md).
    # A real pair keeps its basis: there b00^2 - b01 b10 would cancel instead (the slow rate of a
    # strongly overdamped mode is det / (b + om), relative to det).
    full = np.linalg.inv(x) @ a @ x
    for k in (0, 2):
        b00, b01, b10, b11 = full[k, k], full[k, k + 1], full[k + 1, k], full[k + 1, k + 1]
        if 0.25 * (b00 - b11) ** 2 + b01 * b10 >= 0.0:
            continue  # real eigenvalues
        angle = 0.5 * math.atan2(-(b00 - b11), b01 + b10)
        c, s = math.cos(angle), math.sin(angle)
        first = x[:, k].copy()
        x[:, k] = c * first + s * x[:, k + 1]
        x[:, k + 1] = -s * first + c * x[:, k + 1]
    x_inv = np.linalg.inv(x)
    blocks = np.empty((2, 2, 2))
    full = x_inv @ a @ x
    blocks[0] = full[0:2, 0:2]
    blocks[1] = full[2:4, 2:4]
    for k in range(2):  # a complex pair's diagonal: equal to rounding, made exactly equal
        b00, b01, b10, b11 = blocks[k, 0, 0], blocks[k, 0, 1], blocks[k, 1, 0], blocks[k, 1, 1]
        if 0.25 * (b00 - b11) ** 2 + b01 * b10 < 0.0:
            blocks[k, 0, 0] = blocks[k, 1, 1] = 0.5 * (b00 + b11)
    return x, x_inv, blocks


@njit
def _companion(block):
    """R with (u, u') = R z, coordinates in which a 2x2 block is a damped oscillator.

    u = r.z for a row r; then u'' = tr(B) u' - det(B) u (Cayley-Hamilton), an oscillator with
    b = -tr(B)/2 >= 0 and w^2 = det(B) > 0 for these stable blocks. Of three choices of r the
    best conditioned R = [r; r B] is taken.
    """
    best = np.eye(2)
    quality = -1.0
    for choice in range(3):
        r = np.array([1.0, 0.0]) if choice == 0 else np.array([0.0, 1.0])
        if choice == 2:
            r = np.array([1.0, 1.0])
        rb = r @ block
        det = r[0] * rb[1] - r[1] * rb[0]
        q = abs(det) / (math.sqrt(r @ r) * math.sqrt(rb @ rb) + 1e-300)
        if q > quality:
            quality = q
            best = np.empty((2, 2))
            best[0], best[1] = r, rb
    return best


@njit
def _companion_row(row, companion):
    """(alpha, beta) with row . z = alpha u + beta u' for (u, u') = R z (row times R^-1)."""
    det = companion[0, 0] * companion[1, 1] - companion[0, 1] * companion[1, 0]
    out = np.empty(2)
    out[0] = (row[0] * companion[1, 1] - row[1] * companion[1, 0]) / det
    out[1] = (row[1] * companion[0, 0] - row[0] * companion[0, 1]) / det
    return out


@njit
def _block_coefficient(row, block, companion, power):
    """c with |row . B^power z| <= c sqrt(2 E) for the block's oscillator energy E."""
    ell = row.copy()
    for _ in range(power):
        ell = ell @ block
    ell = _companion_row(ell, companion)
    omega = math.sqrt(block[0, 0] * block[1, 1] - block[0, 1] * block[1, 0])
    return math.hypot(ell[0] / omega, ell[1])  # Cauchy-Schwarz on the energy


@njit
def _overdamped_rates(block):
    """Decay rates (slow, fast) of a strongly overdamped block, or (0, 0).

    Used only when the rates differ by at least OVERDAMPED_GAP of the faster, so that splitting
    a state into the two real exponentials loses little to cancellation.
    """
    b = -0.5 * (block[0, 0] + block[1, 1])
    w2 = block[0, 0] * block[1, 1] - block[0, 1] * block[1, 0]
    d = b * b - w2
    if d <= 0.0:
        return np.zeros(2)
    om = math.sqrt(d)
    fast = b + om
    slow = w2 / fast  # b - om without cancellation
    if fast - slow < OVERDAMPED_GAP * fast:
        return np.zeros(2)
    out = np.empty(2)
    out[0], out[1] = slow, fast
    return out


@njit
def _overdamped_bound(rates, alpha_beta, u, du, power):
    """Bound on |d^power/dt^power (alpha u + beta u')| for all later times of the phase.

    In a block with real rates s < f, u = A e^{-s t} + B e^{-f t}, so the functional's
    derivative is a sum of two decaying exponentials and never exceeds its terms' sizes now:
    |A| s^p |alpha - beta s| + |B| f^p |alpha - beta f|. Far tighter than the energy bound for
    a slow overdamped mode (whose energy also counts w^2 u'^2 >> s^2 u'^2). Inflated by
    OVERDAMPED_SAFETY for the rounding of A and B.
    """
    slow, fast = rates[0], rates[1]
    gap = fast - slow
    a = (du + fast * u) / gap
    b = -(du + slow * u) / gap
    alpha, beta = alpha_beta[0], alpha_beta[1]
    bound = abs(a) * slow**power * abs(alpha - beta * slow)
    bound += abs(b) * fast**power * abs(alpha - beta * fast)
    return bound * OVERDAMPED_SAFETY


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
    root = math.sqrt(fp * fp + 2.0 * bound * f)
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
    solver (twoball.stack).
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

    Returns (event, tau, x1, eta, v1, eta') with tau the time into the phase. horizon is a known
    event time (apex or end of the run) with its event code; prepared is what :func:`prepare`
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
    for _ in range(MAX_STEPS_PER_PHASE):
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
            return event, best, y1, y2, w1, w2
        if kind == BOTH and _at_rest(
            roots, params, rest, rates, mode_rows, block_states, tol_state
        ):
            return EVENT_REST, tau, y1, y2, w1, w2
        if tau + step >= horizon:
            y1, y2, w1, w2, _, _ = state_at(
                kind, horizon, x1, eta, v1, deta, params, x, x_inv, blocks, y_rest
            )
            return horizon_event, horizon, y1, y2, w1, w2
        if not 0.0 < step < np.inf:
            return EVENT_STUCK, tau, x1, eta, v1, deta
        tau += step
        last_step = step
    return EVENT_STEPS, tau, x1, eta, v1, deta


class RunOutcome(NamedTuple):
    """What :func:`run` returns (a named tuple inside numba too)."""

    status: int  # a twoball.errors.Status value
    end_time: float
    apex_t: np.ndarray  # (n_apex,) times of the upper ball's apexes
    apex_h: np.ndarray  # (n_apex,) their heights X2
    ball_contacts_first: int  # ball contacts that start before the first apex
    floor_contacts_first: int
    contacts: np.ndarray  # (n, 3): contact, start, end (empty unless recorded)
    # (n, 7): t, kind, x1, eta, v1, eta' at each phase start and the phase's own duration tau
    # (the difference of two rounded start times is not; benchmarks/phase_audit.py needs it);
    # empty unless recorded
    phases: np.ndarray


@njit
def _room_for_one(rows, n):
    """``rows`` if it has a row free after the first ``n``, else a copy twice as long."""
    if n < rows.shape[0]:
        return rows
    grown = np.empty((max(2 * rows.shape[0], 8), rows.shape[1]))
    grown[:n] = rows[:n]
    return grown


@njit
def run(x1, x2, apexes_wanted, t_end, prepared, record_contacts, record_phases):
    """Run from rest at heights (x1, x2) until the wanted apex, t_end, or rest.

    Returns a :class:`RunOutcome`. Contacts and phases are recorded only when asked (the arrays
    are empty otherwise); the apex table grows as apexes come, so a run to a time with no apex
    limit allocates only what it finds.
    """
    # the state in the relative coordinates of state_at; eta is exact (Sterbenz) for a gap
    # below the drop height
    eta = x2 - x1
    v1 = 0.0
    deta = 0.0
    t = 0.0
    kind = FREE
    # The upper ball's apex is found from its velocity v1 + eta', which after an apex is zero
    # only to rounding; an apex is looked for again only once a ball contact has ended (only
    # the ball contact can lift the upper ball), rather than zeroing eta' there, which would
    # move the overlap's rate by the lower ball's rounding.
    rising = False
    apexes = np.empty((min(apexes_wanted, 64), 2))  # rows: t, h
    n_apex = 0
    ball_first = 0
    floor_first = 0
    start = np.zeros(2)
    contacts = np.empty((64 if record_contacts else 0, 3))
    n_contacts = 0
    phases = np.empty((64 if record_phases else 0, 7))
    n_phases = 0
    status = STATUS_PHASES
    entered_by = -1  # the contact whose switch began the current phase
    # A state that leaves the both-contact phase carries the rounding of its closed form about
    # the static rest (~ mu ulp for a heavy upper ball); later phases must not take that for an
    # overlap, or a contact that just opened closes again at once, for ever.
    stepping = constants(prepared)
    params, y_rest = stepping.params, stepping.y_rest
    both_offset = ROUNDING * params[P_NOISE] * _rest_size(y_rest)
    carried = 0.0
    for _ in range(MAX_PHASES):
        if record_phases:
            phases = _room_for_one(phases, n_phases)
            row = phases[n_phases]
            row[0], row[1], row[2], row[3], row[4], row[5] = t, kind, x1, eta, v1, deta
            n_phases += 1
        horizon = t_end - t
        horizon_event = EVENT_TIME
        v2 = v1 + deta
        if rising and (kind & 2) == 0 and v2 > 0.0 and v2 < horizon:
            horizon = v2  # the upper ball flies freely: its apex is exactly v2 away
            horizon_event = EVENT_APEX
        event, tau, x1, eta, v1, deta = advance_phase(
            kind, t, x1, eta, v1, deta, horizon, horizon_event, stepping, entered_by, carried
        )
        if record_phases:
            phases[n_phases - 1, 6] = tau
        if kind == BOTH:  # the state leaves it with the rounding of its offset (see below)
            carried = both_offset
        entered_by = event if event in (EVENT_FLOOR, EVENT_BALL) else -1
        t += tau
        if event in (EVENT_FLOOR, EVENT_BALL):
            bit = 1 << event
            if kind & bit:
                rising = rising or event == EVENT_BALL
                if record_contacts:
                    contacts = _room_for_one(contacts, n_contacts)
                    row = contacts[n_contacts]
                    row[0], row[1], row[2] = event, start[event], t
                    n_contacts += 1
            else:
                # A contact closing meets its overlap at zero. Found as a root, the overlap there
                # is zero only to the rounding of its terms (the upper ball's fall from thousands
                # above: ~1e-12, where a stiff ball contact's whole compression is ~1): carried
                # into the contact, that start would outweigh every other error of the bounce.
                # So the root is taken as exact (a shift of the switch by rounding / speed).
                if event == EVENT_FLOOR and v1 < 0.0:
                    x1 = 0.0
                elif event == EVENT_BALL and deta < 0.0:
                    eta = 0.0
                start[event] = t
                if n_apex == 0:
                    if event == EVENT_BALL:
                        ball_first += 1
                    else:
                        floor_first += 1
            kind ^= bit
        elif event == EVENT_APEX:
            rising = False
            apexes = _room_for_one(apexes, n_apex)
            apexes[n_apex, 0] = t
            apexes[n_apex, 1] = x1 + eta
            n_apex += 1
            if n_apex == apexes_wanted:
                status = STATUS_DONE
                break
        elif event == EVENT_TIME:
            status = STATUS_DONE
            break
        elif event == EVENT_REST:
            status = STATUS_REST
            break
        elif event == EVENT_STEPS:
            status = STATUS_PHASES
            break
        else:
            status = STATUS_STUCK
            break
    if record_contacts:
        # contacts still open at the end of the run end there
        for contact in range(2):
            if kind & (1 << contact):
                contacts = _room_for_one(contacts, n_contacts)
                row = contacts[n_contacts]
                row[0], row[1], row[2] = contact, start[contact], t
                n_contacts += 1
    return RunOutcome(
        status=status,
        end_time=t,
        apex_t=apexes[:n_apex, 0].copy(),
        apex_h=apexes[:n_apex, 1].copy(),
        ball_contacts_first=ball_first,
        floor_contacts_first=floor_first,
        contacts=contacts[:n_contacts],
        phases=phases[:n_phases],
    )


@njit(nogil=True)
def run_block(mu, zeta01, zeta12, x2_0, height, apex_h, apex_t, contacts, status):
    """Run every drop of a block to its second apex, compiled, with the GIL released (the batch
    path of the sweep; docs/model.md, "What is measured").

    mu (nm), zeta01 (ne), zeta12 (ne, nm), x2_0 (ne, nt); outputs (ne, nm, nt): apex_h and
    apex_t with a leading axis of 2, pre-filled with NaN; contacts (ball contacts before the
    first apex, NaN without one) and status (int8, :class:`twoball.errors.Status`). One
    :func:`prepare` serves a whole row of tau_ratio; nothing but apexes and counts is recorded.
    """
    for i in range(x2_0.shape[0]):
        for j in range(mu.shape[0]):
            prepared = prepare(mu[j], zeta01[i], zeta12[i, j])
            for k in range(x2_0.shape[1]):
                outcome = run(height, x2_0[i, k], 2, np.inf, prepared, False, False)
                n_apex = outcome.apex_t.size
                for a in range(n_apex):
                    apex_t[a, i, j, k] = outcome.apex_t[a]
                    apex_h[a, i, j, k] = outcome.apex_h[a]
                contacts[i, j, k] = outcome.ball_contacts_first if n_apex > 0 else np.nan
                status[i, j, k] = outcome.status


@njit
def sample(phases, times, prepared):
    """Exact state and forces at the given times from the recorded phases.

    Returns an array (len(times), 6): x1, x2, v1, v2, f01, f12.
    """
    params, x, x_inv = prepared.params, prepared.x, prepared.x_inv
    blocks, y_rest = prepared.blocks, prepared.y_rest
    z01, z12 = params[P_Z01], params[P_Z12]
    out = np.empty((times.size, 6))
    starts = phases[:, 0]
    for i in range(times.size):
        index = max(np.searchsorted(starts, times[i], side="right") - 1, 0)
        row = phases[index]
        kind = int(row[1])
        x1, eta, v1, deta, _, _ = state_at(
            kind,
            times[i] - row[0],
            row[2],
            row[3],
            row[4],
            row[5],
            params,
            x,
            x_inv,
            blocks,
            y_rest,
        )
        f01 = max(-(x1 + 2.0 * z01 * v1), 0.0) if kind & 1 else 0.0
        f12 = max(-(eta + 2.0 * z12 * deta), 0.0) if kind & 2 else 0.0
        row_out = out[i]
        row_out[0], row_out[1], row_out[2], row_out[3] = x1, x1 + eta, v1, v1 + deta
        row_out[4], row_out[5] = f01, f12
    return out


@njit
def run_drop(mu, z01, z12, x1, x2, apexes_wanted, t_end):
    """:func:`prepare` and :func:`run` (contacts recorded, no phases) in one compiled call, so
    that nothing of the preparation crosses into Python (``simulate``'s common path)."""
    return run(x1, x2, apexes_wanted, t_end, prepare(mu, z01, z12), True, False)


def solve(
    drop: Drop,
    apexes: int,
    t_end: float,
    *,
    rtol: float | None = None,
    atol: float | None = None,
    dense_output: bool = False,
) -> Outcome:
    """Run the exact solver on a validated drop; see :func:`twoball.simulate`. It has no
    tolerances (``rtol`` and ``atol`` are refused: they belong to the other methods).

    With ``dense_output`` the phases are recorded, and the outcome's ``evaluate`` gives the exact
    state at any times.
    """
    if rtol is not None or atol is not None:
        raise ParameterError("rtol and atol apply to the scipy methods only, not to 'exact'")
    evaluate = plot_times = None
    if not dense_output:
        out = run_drop(
            drop.mu, drop.zeta01, drop.zeta12, drop.x1_0, drop.x2_0, max(apexes, 1), t_end
        )
    else:
        prepared = prepare(drop.mu, drop.zeta01, drop.zeta12)
        out = run(drop.x1_0, drop.x2_0, max(apexes, 1), t_end, prepared, True, True)
        phases = out.phases

        def evaluate(times: np.ndarray) -> np.ndarray:
            return sample(phases, np.asarray(times, dtype=float), prepared)

        plot_times = default_times(phases, out.end_time)
    status = Status(out.status)
    return Outcome(
        apex_t=out.apex_t.tolist(),
        apex_h=out.apex_h.tolist(),
        contacts=out.contacts,
        end_time=out.end_time,
        status=status,
        message=status.message or None,
        contacts_first=out.ball_contacts_first,
        floor_contacts_first=out.floor_contacts_first,
        evaluate=evaluate,
        plot_times=plot_times,
    )


def default_times(phases: np.ndarray, end: float, points: int = 2001) -> np.ndarray:
    """Plotting times: an even grid over the run plus 17 points inside every phase, so that
    brief contacts are drawn too."""
    starts = phases[:, 0]
    stops = np.append(starts[1:], end)
    inside = np.linspace(starts, stops, 17).ravel()
    return np.unique(np.concatenate([np.linspace(0.0, end, points), inside]))
