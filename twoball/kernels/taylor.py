"""Taylor series of the Hertz stack's time-changed motion, for the contact phases of
:mod:`twoball.kernels.hertz` (docs/stacks.md, "Why a Taylor series of the time-changed motion").

With rho_c = sqrt(delta_c) for each contact in the series and dt = J dtau, J the product of
their rho, the motion is polynomial in (t, w, w', rho) (w, w' what the contact forces add to each
ball's parabola since the step's start), so every coefficient of its Taylor series in tau follows
from the lower ones by the recurrences of products (Cauchy products): :func:`_series`. The step
is Jorba and Zou's, the last term of every series at :data:`TOLERANCE` of its scale, with the
radius of convergence taken from the last :data:`LAST` coefficients (:func:`_taylor_step`). The
series are each step's dense output: the contacts' switching functions on them
(:func:`_functions`), a switch found by regula falsi (:func:`_function_root`), a moment of the
clock by Newton's method (:func:`_time_root`). Bounds from a step's coefficients say where no
switch needs certifying: each release the one root of rho in the step (:func:`_releases_shown`),
no clamp within reach (:func:`_clamp_reachable`).
"""

from __future__ import annotations

import math

from twoball.jit import njit

ORDER = 20  # Taylor coefficients per step (the series' degree)
TOLERANCE = 1e-16  # each series' last term at the step, relative to its variable's scale
LAST = 6  # coefficients that estimate the radius of convergence (more than a lacunary gap)
ROOT_TOLERANCE = TOLERANCE ** (1.0 / ORDER)
# the first-order rates (relative to scale) within which tau is left unscaled (:func:`_pace`):
# their powers to ORDER stay within 2^(+-600), and results there are those before it, bit for bit
RATES_IN_RANGE = 2.0**30


@njit(borrow=True)
def _series(
    masses, lam, used, moving, on, count, deta0, scales, S, D, Q, Cb, L, F, G, J, Jo, Pre, Suf
):  # fmt: skip
    """Taylor coefficients 1..ORDER in tau of a step's series (rows of S, coefficient 0 given):
    S[0] the clock t, S[1 + j] w_j and S[1 + n + j] w_j' (the displacement and velocity the
    contact forces add to ball j's parabola since the step's start, for the ``moving`` balls),
    S[1 + 2n + c] rho_c = sqrt(delta_c) (the ``on`` contacts, the first ``count`` of the ``used``
    ones), with dt = J dtau / K, J the product of their rho; ``D`` receives the series of every
    eta_c'.

    K (:func:`_pace`) is 1, or, where it is far from 1, a power of two near the fastest
    first-order rate of the series, each relative to its scale (``scales``, the rows of S): a
    constant, so the motion is the same on a clock scaled exactly, but with K = 1 the
    coefficients go as J^k, and J, a product of up to N rho, under- or overflowed by order 20
    (docs/stacks.md, "Why a Taylor series of the time-changed motion").

    Each coefficient k of a product is the Cauchy sum over m = 0..k in that order; the sums
    that do not wait for each other (a contact's rho^2, rho^3 and force; a ball's J w' and J
    times its forces) run in one loop, each sum's last term added once the coefficient it
    needs is known, and a lone contact's J / rho = 1 is not multiplied out: the same bits as
    one product after the other, in 0.7 of the time (docs/performance.md, "The Stack scene's
    forces": a product's additions wait for each other, and the loops' sums did not overlap)."""
    n = masses.size
    W, U, R = 1, 1 + n, 1 + 2 * n
    pace = 1.0  # 1 / K, chosen once the first-order coefficients (K = 1) are known
    for k in range(ORDER):
        if k == 1:
            pace = _pace(moving, on, count, S, scales)
        for c in range(n):
            rate = deta0[c] if k == 0 else 0.0
            if c == 0:
                rate -= S[0, k]
            if moving[c]:
                rate += S[U + c, k]
            if c >= 1 and moving[c - 1]:
                rate -= S[U + c - 1, k]
            D[c, k] = rate
        # J, and each contact's J / rho_c (the product of the others' rho), with two or more
        if count == 1:
            J[k] = S[R + on[0], k]
        else:
            Pre[0, k] = S[R + on[0], k]
            for i in range(1, count):
                total = 0.0
                for m in range(k + 1):
                    total += Pre[i - 1, m] * S[R + on[i], k - m]
                Pre[i, k] = total
            Suf[count - 1, k] = S[R + on[count - 1], k]
            for i in range(count - 2, 0, -1):
                total = 0.0
                for m in range(k + 1):
                    total += S[R + on[i], m] * Suf[i + 1, k - m]
                Suf[i, k] = total
            J[k] = Pre[count - 1, k]
            Jo[on[0], k] = Suf[1, k]
            Jo[on[count - 1], k] = Pre[count - 2, k]
            for i in range(1, count - 1):
                total = 0.0
                for m in range(k + 1):
                    total += Pre[i - 1, m] * Suf[i + 1, k - m]
                Jo[on[i], k] = total
        after = pace / (k + 1)  # exact: pace is a power of two
        # each contact's rho^2, rho^3 and force (rho^3 (1 - lam eta')), and rho's next term
        for i in range(count):
            c = on[i]
            row = R + c
            L[c, k] = (1.0 if k == 0 else 0.0) - lam[c] * D[c, k]
            square, cube, force = 0.0, 0.0, 0.0
            for m in range(k):
                square += S[row, m] * S[row, k - m]
                cube += Q[c, m] * S[row, k - m]
                force += Cb[c, m] * L[c, k - m]
            square += S[row, k] * S[row, 0]
            cube += square * S[row, 0]
            Q[c, k], Cb[c, k], F[c, k] = square, cube, force + cube * L[c, 0]
            rate = D[c, k]  # J / rho_c = 1 for a lone contact
            if count > 1:
                rate = 0.0
                for m in range(k + 1):
                    rate += Jo[c, m] * D[c, k - m]
            S[row, k + 1] = -0.5 * rate * after
        S[0, k + 1] = J[k] * after
        for j in range(n):
            if moving[j]:
                below = F[j, k] if used[j] else 0.0
                above = F[j + 1, k] if j + 1 < n and used[j + 1] else 0.0
                G[j, k] = (below - above) / masses[j]
                w, speed = 0.0, 0.0
                for m in range(k + 1):
                    w += J[m] * S[U + j, k - m]
                    speed += J[m] * G[j, k - m]
                S[W + j, k + 1] = w * after
                S[U + j, k + 1] = speed * after


@njit
def _pace(moving, on, count, S, scales) -> float:
    """1 / K for :func:`_series`, K a power of two near the largest first-order coefficient of
    the series (computed with K = 1), each relative to its scale, and those coefficients moved to
    the clock tau K (exact: a power of two). Their sizes in tau are those of J and of the
    products of the other contacts' rho, which span hundreds of orders over a stack (seven
    contacts' rho of 1e-8 to 1 gave J = 1e-25, and the clock's last six coefficients underflowed
    to zero: an infinite step, a clock at 3e260; seven of 110 gave J = 1e14, and NaN); relative to K
    the fastest is about 1, and the coefficients to order 20 are within the range of a double.
    Within :data:`RATES_IN_RANGE` K = 1."""
    n = moving.size
    W, U, R = 1, 1 + n, 1 + 2 * n
    fastest = abs(S[0, 1]) / scales[0]
    for i in range(count):
        fastest = max(fastest, abs(S[R + on[i], 1]) / scales[R + on[i]])
    for j in range(n):
        if moving[j]:
            fastest = max(fastest, abs(S[U + j, 1]) / scales[U + j])
    if not 0.0 < fastest < math.inf or 1.0 / RATES_IN_RANGE <= fastest <= RATES_IN_RANGE:
        return 1.0
    pace = math.ldexp(1.0, -math.frexp(fastest)[1])
    S[0, 1] *= pace
    for i in range(count):
        S[R + on[i], 1] *= pace
    for j in range(n):
        if moving[j]:
            S[W + j, 1] *= pace
            S[U + j, 1] *= pace
    return pace


@njit
def _value(S, row, tau) -> float:
    """Series ``row`` of S at tau (Horner)."""
    total = 0.0
    for k in range(ORDER, -1, -1):
        total = total * tau + S[row, k]
    return total


@njit
def _rate(S, row, tau) -> float:
    """The derivative in tau of series ``row`` at tau."""
    total = 0.0
    for k in range(ORDER, 0, -1):
        total = total * tau + k * S[row, k]
    return total


@njit
def _taylor_step(S, scales, rows) -> float:
    """The step in tau from the last :data:`LAST` coefficients of the series in ``rows``, each
    relative to its scale: with q_k the largest |c_k| / scale, the radius of convergence is
    about q_k^(-1/k), and the step TOLERANCE^(1/ORDER) times the least of these, which for k =
    ORDER puts the last term at TOLERANCE (Jorba and Zou's rule). Not their last two terms
    only: at a touch the series are lacunary (a lone contact's sqrt(delta) obeys rho'' ~ rho^4
    in tau, so from rho = 0 only every fifth coefficient is nonzero), and two vanishing last
    terms gave steps six times too long (h2 off by 1e-10 at order 24)."""
    largest = 0.0
    for k in range(ORDER + 1 - LAST, ORDER + 1):
        size = 0.0
        for i in range(rows.size):
            size = max(size, abs(S[rows[i], k]) / scales[rows[i]])
        if size > 0.0:
            largest = max(largest, size ** (1.0 / k))
    return ROOT_TOLERANCE / largest if largest > 0.0 else math.inf


@njit
def _time_root(S, target, high) -> float:
    """The tau in (0, high] at which the clock's series reaches ``target`` (it rises on [0,
    high] and reaches at least ``target`` at high): Newton's method, kept in its bracket."""
    low = 0.0
    tau = high
    for _ in range(100):
        value = _value(S, 0, tau) - target
        if value > 0.0:
            high = tau
        elif value < 0.0:
            low = tau
        else:
            return tau
        slope = _rate(S, 0, tau)
        guess = tau - value / slope if slope > 0.0 else 0.5 * (low + high)
        if not low <= guess <= high:
            guess = 0.5 * (low + high)
        if guess == tau or high - low <= 1e-16 * high:
            return guess
        tau = guess
    return tau


@njit
def _motion(S, tau, moving, z) -> float:
    """The clock's s at tau, and z = (w, w') there (zero for a ball in free flight)."""
    n = moving.size
    for j in range(n):
        z[j], z[n + j] = 0.0, 0.0
        if moving[j]:
            z[j], z[n + j] = _value(S, 1 + j, tau), _value(S, 1 + n + j, tau)
    return _value(S, 0, tau)


@njit
def _functions(lam, used, moving, S, tau, eta0, deta0, z, out) -> None:
    """Each contact's switching function at tau, signed to fall through zero at its switch: for
    a contact in the series min(rho, 1 + lam delta'), for another max(eta, lam eta' - 1) (the
    rule of docs/model.md, "Bodies, coordinates, forces": with rho >= 0, -max(-rho^2, g) has
    rho's sign)."""
    n = lam.size
    s = _motion(S, tau, moving, z)
    for c in range(n):
        eta = eta0[c] + deta0[c] * s + z[c] - (z[c - 1] if c >= 1 else 0.0)
        deta = deta0[c] + z[n + c] - (z[n + c - 1] if c >= 1 else 0.0)
        if c == 0:
            eta -= 0.5 * s * s
            deta -= s
        if used[c]:
            out[c] = min(_value(S, 1 + 2 * n + c, tau), 1.0 - lam[c] * deta)
        else:
            out[c] = max(eta, lam[c] * deta - 1.0)


@njit
def _function(lam, used, moving, S, c, tau, eta0, deta0) -> float:
    """Contact c's switching function at tau (as :func:`_functions`, evaluating its series only)."""
    n = lam.size
    s = _value(S, 0, tau)
    rate = deta0[c]
    if moving[c]:
        rate += _value(S, 1 + n + c, tau)
    if c >= 1 and moving[c - 1]:
        rate -= _value(S, n + c, tau)
    if c == 0:
        rate -= s
    if used[c]:
        return min(_value(S, 1 + 2 * n + c, tau), 1.0 - lam[c] * rate)
    eta = eta0[c] + deta0[c] * s
    if moving[c]:
        eta += _value(S, 1 + c, tau)
    if c >= 1 and moving[c - 1]:
        eta -= _value(S, c, tau)
    if c == 0:
        eta -= 0.5 * s * s
    return max(eta, lam[c] * rate - 1.0)


@njit
def _function_root(lam, used, moving, S, c, low, high, eta0, deta0) -> float:
    """The tau in (low, high] where contact c's switching function falls through zero, to
    rounding (the side past the root): regula falsi with Illinois' halving, which keeps the
    bracket and takes a handful of evaluations where bisection took fifty (each evaluating
    every series, the larger part of a run's time)."""
    f_low = _function(lam, used, moving, S, c, low, eta0, deta0)
    f_high = _function(lam, used, moving, S, c, high, eta0, deta0)
    if not f_low > 0.0:
        f_low = 1e-300  # at the root itself: regula falsi falls back to bisection
    side = 0
    for iteration in range(200):
        if high - low <= 1e-16 * high:
            break
        spread = f_high - f_low
        # bisection after 100 steps, where the secant leaves the bracket, and where the ends'
        # values, halved by Illinois' rule, have both underflowed to zero (compiled, the
        # secant's division by zero raised ZeroDivisionError out of the run: a researcher's
        # 5-ball Hertz stack, tests/test_hertz.py)
        bisect = iteration >= 100 or spread == 0.0
        if not bisect:
            middle = (low * f_high - high * f_low) / spread
            bisect = not low < middle < high
        if bisect:
            middle = 0.5 * (low + high)
            if not low < middle < high:
                break
        value = _function(lam, used, moving, S, c, middle, eta0, deta0)
        if value < 0.0:
            high, f_high = middle, value
            if side == -1:
                f_low *= 0.5
            side = -1
        else:
            low, f_low = middle, max(value, 1e-300)
            if side == 1:
                f_high *= 0.5
            side = 1
    return high


@njit
def _releases_shown(S, on, count, R, tau) -> bool:
    """Whether each contact in the series keeps rho > 0 over [0, tau] or has rho' < 0 there (so
    its release, if any, is the one root of rho, shown at the step's end), from bounds on the
    coefficients: rho >= r0 + r1 u - B u^2 / tau^2 (B the negative terms' sum at tau), concave,
    so least at an end; rho' <= r1 + the positive terms' sum."""
    for i in range(count):
        row = R + on[i]
        r0, r1 = S[row, 0], S[row, 1]
        negative, rising = 0.0, 0.0
        power = tau
        for k in range(2, ORDER + 1):
            power *= tau
            term = S[row, k] * power
            negative += min(term, 0.0)
            rising += k * max(term, 0.0) / tau
        if not ((r0 >= 0.0 and r0 + r1 * tau + negative > 0.0) or r1 + rising < 0.0):
            return False
    return True


@njit
def _clamp_reachable(lam, used, active, eta0, D, tau) -> bool:
    """Whether a clamp (lam eta' = 1) can be reached within [0, tau] of the step: a contact in
    the series whose eta' (its series ``D``) can reach 1 / lam there, bounded by its positive
    coefficients, or an open contact still overlapping (its re-push). Without one, every switch
    is a root of an overlap (or of rho), shown at the step's end."""
    for c in range(lam.size):
        if used[c]:
            highest = D[c, 0]
            power = 1.0
            for k in range(1, ORDER):
                power *= tau
                highest += max(D[c, k], 0.0) * power
            if lam[c] * highest >= 1.0:
                return True
        elif not active[c] and eta0[c] < 0.0:
            return True
    return False
