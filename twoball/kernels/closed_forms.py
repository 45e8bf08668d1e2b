"""Closed forms of a damped oscillator and of the both-contact phase's two modes, exact on every
damping branch (docs/model.md, "Bodies, coordinates, forces"): what the two-ball and the N-ball
kernels advance a phase with and bound its future by (:mod:`twoball.kernels.phases` says how).
"""

from __future__ import annotations

import math

import numpy as np

from twoball.jit import njit
from twoball.kernels.codes import ROUNDING

MAX_ROOT_ITERATIONS = 100  # of a bracketed Halley search (it converges in about three)
SUBSPACE_SWEEPS = 4  # refinement sweeps of the both-contact mode split (see _split_modes)
OVERDAMPED_GAP = 0.1  # rates this far apart (relative) split a block into two exponentials
OVERDAMPED_SAFETY = 1.0 + 1e-9  # covers the rounding of that split (relative ~ulp / gap)


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
