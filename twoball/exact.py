"""The exact solver: the model advanced phase by phase in closed form (model.md).

Between switches the equations are linear with constant coefficients, so each phase has a
closed-form solution:

- free flight (no contact): both heights are parabolas;
- floor contact only: the lower ball is a damped oscillator about X1 = -1, the upper ball a
  parabola;
- ball contact only: the centre of mass is a parabola, the overlap X2 - X1 a damped oscillator;
- both contacts: a two-degree-of-freedom damped system, solved by its eigenmodes, or by the
  matrix exponential where the modes are close to defective (eps near exp(-2) with small mu).

The scalar oscillators are written in a form that is exact across the damping branch switch
(under-, critically and overdamped) without cancellation.

Switching times (a contact switching on or off, an apex of the upper ball) are the first roots of
the switching functions F(t) of model.md ("Restitution and damping"): for an inactive contact
F = max(eta, g), which must become negative for the contact to push; for an active contact
F = -g, which reaches zero when the force does.

Why no contact can be missed. Each step starts from a point where F > -tol and moves by the
largest h for which the parabola F + F' h - M h^2 / 2 stays above -tol, where M is a proven
bound on |F''| over the rest of the phase. The bound comes from an energy: the velocity
w = (X1', X2') obeys the homogeneous phase equation M w'' + C w' + K w = 0, so
E_w = w'.M.w'/2 + w.K.w/2 never increases during a phase, and |F''| <= c0 + c1 sqrt(2 E_w) with
constants c0, c1 worked out once per phase type (Cauchy-Schwarz in the energy norm). Between
steps F is therefore certified above -tol; a root can only be approached, never stepped over,
however brief the contact or however tangent the touch. Near a simple root the steps converge
quadratically (the parabola is a second-order model). ``tol`` is a few units of rounding in the
state (16 ulp of |X1| + |X2| + |X1'| + |X2'| + 1); an overlap shallower than that is below what
double precision can represent and is the only thing that can go unnoticed.

The upper ball at rest on the lower one (both contacts active for ever) is also proven rather
than guessed: once the energy of the deviation from the static equilibrium is too small for
either contact force to reach zero, no switch can ever happen again.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from twoball.model import Drop

# Phase kinds: bit 0 floor contact active, bit 1 ball contact active.
FREE, FLOOR, BALL, BOTH = 0, 1, 2, 3

# Events returned by one phase.
EVENT_FLOOR, EVENT_BALL, EVENT_APEX, EVENT_TIME, EVENT_REST, EVENT_STUCK = 0, 1, 2, 3, 4, 5

# Status of a run.
STATUS_DONE, STATUS_REST, STATUS_STUCK, STATUS_PHASES = 0, 1, 2, 3
STATUS_TEXT = {
    STATUS_DONE: "",
    STATUS_REST: "the upper ball came to rest on the lower one",
    STATUS_STUCK: "root finder made no progress (please report: this is a bug)",
    STATUS_PHASES: "phase limit reached",
}

MAX_STEPS_PER_PHASE = 100_000
MAX_PHASES = 1_000_000
MODAL_CONDITION_LIMIT = 1.0e3
ROUNDING = 16.0 * 2.220446049250313e-16  # tolerance in units of relative rounding

# Layout of the per-drop parameter vector passed to the kernel.
P_MU, P_Z01, P_Z12, P_W2, P_F1, P_F2, P_RF, P_RB, P_NOISE = range(9)


@numba.njit(cache=True)
def _oscillator_bound(alpha, beta, b, omega):
    """c1 for s = alpha u + beta u' on u'' + 2 b u' + omega^2 u = 0: |s''| <= c1 sqrt(2 e_w)."""
    return abs(alpha - 2.0 * b * beta) + omega * abs(beta)


@numba.njit(cache=True)
def _coupled_bound(alpha, beta, mass, damping, stiffness):
    """c1 for s = alpha.q + beta.q' in the both-contact phase (energy norm, Cauchy-Schwarz)."""
    gamma = beta / mass
    first = (alpha - damping @ gamma) / np.sqrt(mass)
    return np.sqrt(first @ first) + math.sqrt(max(gamma @ (stiffness @ gamma), 0.0))


@numba.njit(cache=True)
def _rest_coefficient(alpha, beta, mass, stiffness_inv):
    """R with |g(y) - g(y*)| <= R sqrt(2 E_dev), E_dev the energy of the deviation from rest."""
    scaled = beta / np.sqrt(mass)
    return np.sqrt(scaled @ scaled) + math.sqrt(alpha @ (stiffness_inv @ alpha))


@numba.njit(cache=True)
def prepare(mu, z01, z12):
    """What the kernel needs for one drop: parameter vector, bound tables, both-contact modes.

    Returns (params, c0, c1, lam, vec, vec_inv, modal, a_both, y_rest); c0[kind, contact, part]
    + c1[...] sqrt(2 E_w) bounds |F''| (part 0 is eta, part 1 is g).
    """
    w2 = (1.0 + mu) / mu
    nu2 = mu / (1.0 + mu)
    b12, om12 = z12 * w2, math.sqrt(w2)
    mass = np.array([1.0, mu])
    stiffness = np.array([[2.0, -1.0], [-1.0, 1.0]])
    damping = np.array([[2 * z01 + 2 * z12, -2 * z12], [-2 * z12, 2 * z12]])
    c0 = np.zeros((4, 2, 2))
    c1 = np.zeros((4, 2, 2))
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
    floor_eta, floor_g = np.array([1.0, 0.0]), np.array([2 * z01, 0.0])
    ball_eta, ball_g = np.array([-1.0, 1.0]), np.array([-2 * z12, 2 * z12])
    zero = np.zeros(2)
    c1[BOTH, 0, 0] = _coupled_bound(floor_eta, zero, mass, damping, stiffness)
    c1[BOTH, 0, 1] = _coupled_bound(floor_eta, floor_g, mass, damping, stiffness)
    c1[BOTH, 1, 0] = _coupled_bound(ball_eta, zero, mass, damping, stiffness)
    c1[BOTH, 1, 1] = _coupled_bound(ball_eta, ball_g, mass, damping, stiffness)
    stiffness_inv = np.array([[1.0, 1.0], [1.0, 2.0]])
    a_both = np.zeros((4, 4))
    a_both[0, 2] = a_both[1, 3] = 1.0
    for i in range(2):
        for j in range(2):
            a_both[2 + i, j] = -stiffness[i, j] / mass[i]
            a_both[2 + i, 2 + j] = -damping[i, j] / mass[i]
    lam, vec = np.linalg.eig(a_both.astype(np.complex128))
    vec_inv = np.linalg.inv(vec)
    condition = np.abs(vec).sum(axis=0).max() * np.abs(vec_inv).sum(axis=0).max()  # 1-norm
    modal = condition < MODAL_CONDITION_LIMIT
    params = np.empty(9)
    params[P_MU], params[P_Z01], params[P_Z12], params[P_W2] = mu, z01, z12, w2
    params[P_F1] = 1.0 + mu  # -g01 at rest: the floor carries both weights
    params[P_F2] = mu  # -g12 at rest: the lower ball carries the upper one
    params[P_RF] = _rest_coefficient(floor_eta, floor_g, mass, stiffness_inv)
    params[P_RB] = _rest_coefficient(ball_eta, ball_g, mass, stiffness_inv)
    params[P_NOISE] = condition if modal else 16.0  # rounding growth of the both-contact state
    y_rest = np.array([-(1.0 + mu), -(1.0 + 2.0 * mu), 0.0, 0.0])
    return params, c0, c1, lam, vec, vec_inv, modal, a_both, y_rest


@numba.njit(cache=True)
def _oscillator(u0, v0, b, w2, tau):
    """u, u', u'' at tau for u'' + 2 b u' + w2 u = 0 from (u0, v0), on every damping branch."""
    d = w2 - b * b
    if d > 0.0:
        om = math.sqrt(d)
        decay = math.exp(-b * tau)
        cos_part = decay * math.cos(om * tau)
        sin_part = decay * math.sin(om * tau) / om
    elif d < 0.0:
        om = math.sqrt(-d)
        slow = math.exp(-(w2 / (b + om)) * tau)  # exp(-(b - om) tau) without cancellation
        fast = math.exp(-2.0 * om * tau)
        cos_part = 0.5 * slow * (1.0 + fast)
        sin_part = slow * (-math.expm1(-2.0 * om * tau)) / (2.0 * om)
    else:
        decay = math.exp(-b * tau)
        cos_part = decay
        sin_part = tau * decay
    u = cos_part * u0 + sin_part * (v0 + b * u0)
    v = cos_part * v0 - sin_part * (w2 * u0 + b * v0)
    return u, v, -2.0 * b * v - w2 * u


@numba.njit(cache=True)
def _expm4(a, tau):
    """exp(a tau) for a 4x4 matrix: scaling and squaring of a Taylor series (exact to rounding)."""
    b = a * tau
    norm = 0.0
    for i in range(4):
        row = 0.0
        for j in range(4):
            row += abs(b[i, j])
        norm = max(norm, row)
    squarings = 0
    while norm > 0.25:
        norm *= 0.5
        squarings += 1
    b = b / (2.0**squarings)
    result = np.eye(4)
    term = np.eye(4)
    for k in range(1, 20):
        term = term @ b / k
        result = result + term
    for _ in range(squarings):
        result = result @ result
    return result


@numba.njit(cache=True)
def state_at(kind, tau, x1, x2, v1, v2, params, lam, vec, vec_inv, modal, a_both, y_rest):
    """Exact state (x1, x2, v1, v2, a1, a2) a time tau into a phase of the given kind."""
    mu, z01, z12, w2 = params[P_MU], params[P_Z01], params[P_Z12], params[P_W2]
    if kind == FREE:
        return (
            x1 + tau * (v1 - 0.5 * tau),
            x2 + tau * (v2 - 0.5 * tau),
            v1 - tau,
            v2 - tau,
            -1.0,
            -1.0,
        )
    if kind == FLOOR:
        u, v, a = _oscillator(x1 + 1.0, v1, z01, 1.0, tau)
        return u - 1.0, x2 + tau * (v2 - 0.5 * tau), v, v2 - tau, a, -1.0
    if kind == BALL:
        total = 1.0 + mu
        xc = (x1 + mu * x2) / total
        vc = (v1 + mu * v2) / total
        eta, deta, ddeta = _oscillator(x2 - x1, v2 - v1, z12 * w2, w2, tau)
        xc_t = xc + tau * (vc - 0.5 * tau)
        vc_t = vc - tau
        share1, share2 = mu / total, 1.0 / total
        return (
            xc_t - share1 * eta,
            xc_t + share2 * eta,
            vc_t - share1 * deta,
            vc_t + share2 * deta,
            -1.0 - share1 * ddeta,
            -1.0 + share2 * ddeta,
        )
    dev = np.empty(4)
    dev[0] = x1 - y_rest[0]
    dev[1] = x2 - y_rest[1]
    dev[2] = v1
    dev[3] = v2
    out = np.empty(4)
    if modal:
        coef = vec_inv @ dev.astype(np.complex128)
        for i in range(4):
            coef[i] *= np.exp(lam[i] * tau)
        now = vec @ coef
        rate = vec @ (coef * lam)
        for i in range(4):
            out[i] = now[i].real
        return (
            y_rest[0] + out[0],
            y_rest[1] + out[1],
            out[2],
            out[3],
            rate[2].real,
            rate[3].real,
        )
    out = _expm4(a_both, tau) @ dev
    acc = a_both @ out
    return y_rest[0] + out[0], y_rest[1] + out[1], out[2], out[3], acc[2], acc[3]


@numba.njit(cache=True)
def _safe_step(f, fp, bound):
    """Largest h with f + fp h - bound h^2/2 > 0 on [0, h), for f > 0."""
    if bound <= 0.0:
        return f / (-fp) if fp < 0.0 else np.inf
    root = math.sqrt(fp * fp + 2.0 * bound * f)
    if fp >= 0.0:
        return (fp + root) / bound
    return 2.0 * f / (root - fp)


@numba.njit(cache=True)
def _switching(
    kind, contact, active, x1, x2, v1, v2, a1, a2, params, c0, c1, energy_root, tol_state, clock
):
    """One contact's switching function: (F, F', tol, step certified above -tol).

    tol is the rounding in F: that of the state, plus |F'| times the rounding of the clock.
    """
    if contact == 0:
        eta, deta = x1, v1
        zeta = params[P_Z01]
        dd = a1
    else:
        eta, deta = x2 - x1, v2 - v1
        zeta = params[P_Z12]
        dd = a2 - a1
    g = eta + 2.0 * zeta * deta
    dg = deta + 2.0 * zeta * dd
    bound_eta = c0[kind, contact, 0] + c1[kind, contact, 0] * energy_root
    bound_g = c0[kind, contact, 1] + c1[kind, contact, 1] * energy_root
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


@numba.njit(cache=True)
def _energy_root(kind, v1, v2, a1, a2, params):
    """sqrt(2 E_w) of the phase's velocity energy, non-increasing within the phase."""
    if kind == FREE:
        return 0.0
    if kind == FLOOR:
        return math.sqrt(a1 * a1 + v1 * v1)
    if kind == BALL:
        d, dd = v2 - v1, a2 - a1
        return math.sqrt(dd * dd + params[P_W2] * d * d)
    mu = params[P_MU]
    kinetic = a1 * a1 + mu * a2 * a2
    potential = 2.0 * v1 * v1 - 2.0 * v1 * v2 + v2 * v2
    return math.sqrt(kinetic + potential)


@numba.njit(cache=True)
def _at_rest(x1, x2, v1, v2, params, y_rest, tol):
    """True when neither contact of the both-contact phase can ever switch off again."""
    mu = params[P_MU]
    d1, d2 = x1 - y_rest[0], x2 - y_rest[1]
    energy = v1 * v1 + mu * v2 * v2 + 2.0 * d1 * d1 - 2.0 * d1 * d2 + d2 * d2
    root = math.sqrt(max(energy, 0.0))
    return params[P_F1] - params[P_RF] * root > tol and params[P_F2] - params[P_RB] * root > tol


@numba.njit(cache=True)
def advance_phase(
    kind,
    t,
    x1,
    x2,
    v1,
    v2,
    horizon,
    horizon_event,
    params,
    c0,
    c1,
    lam,
    vec,
    vec_inv,
    modal,
    a_both,
    y_rest,
):
    """Advance one phase, started at time t, to its first event.

    Returns (event, tau, x1, x2, v1, v2) with tau the time into the phase. horizon is a known
    event time (apex or end of the run) with its event code.
    """
    noise = params[P_NOISE] if kind == BOTH else 1.0
    size = 1.0 + abs(x1) + abs(x2)
    speed = abs(v1) + abs(v2)
    floor_on = (kind & 1) != 0
    ball_on = (kind & 2) != 0
    tau = 0.0
    for _ in range(MAX_STEPS_PER_PHASE):
        y1, y2, w1, w2, a1, a2 = state_at(
            kind, tau, x1, x2, v1, v2, params, lam, vec, vec_inv, modal, a_both, y_rest
        )
        energy_root = _energy_root(kind, w1, w2, a1, a2, params)
        # rounding of the closed form at tau: its largest terms are x0, v0 tau and tau^2/2
        tol_state = ROUNDING * noise * (size + speed * (1.0 + tau) + tau * tau)
        clock = 1.0 + t + tau
        step = horizon - tau
        event = -1
        best = np.inf
        for contact in range(2):
            active = floor_on if contact == 0 else ball_on
            value, rate, tol, h = _switching(
                kind,
                contact,
                active,
                y1,
                y2,
                w1,
                w2,
                a1,
                a2,
                params,
                c0,
                c1,
                energy_root,
                tol_state,
                clock,
            )
            if value <= -tol or (value <= tol and rate < 0.0):
                # At a root to rounding: one Newton correction, never past the certified step.
                shift = 0.0
                if rate < 0.0:
                    shift = min(max(value, 0.0) / -rate, h)
                if tau + shift < best:
                    best, event = tau + shift, contact
            else:
                step = min(step, h)
        if event >= 0:
            y1, y2, w1, w2, _, _ = state_at(
                kind, best, x1, x2, v1, v2, params, lam, vec, vec_inv, modal, a_both, y_rest
            )
            return event, best, y1, y2, w1, w2
        if kind == BOTH and _at_rest(y1, y2, w1, w2, params, y_rest, tol_state):
            return EVENT_REST, tau, y1, y2, w1, w2
        if tau + step >= horizon:
            y1, y2, w1, w2, _, _ = state_at(
                kind, horizon, x1, x2, v1, v2, params, lam, vec, vec_inv, modal, a_both, y_rest
            )
            return horizon_event, horizon, y1, y2, w1, w2
        if not 0.0 < step < np.inf:
            break
        tau += step
    return EVENT_STUCK, tau, x1, x2, v1, v2


@numba.njit(cache=True)
def run(
    x1,
    x2,
    apexes_wanted,
    t_end,
    params,
    c0,
    c1,
    lam,
    vec,
    vec_inv,
    modal,
    a_both,
    y_rest,
    record_contacts,
    record_phases,
):
    """Run from rest at heights (x1, x2) until the wanted apex, t_end, or rest.

    Returns (status, t, apex_t[apexes_wanted], apex_h[...], n_apex, ball_first, floor_first,
    contacts (n, 3: contact, start, end), phases (n, 6: t, kind, x1, x2, v1, v2)).
    Contacts and phases are recorded only when asked (the arrays are empty otherwise).
    """
    v1 = 0.0
    v2 = 0.0
    t = 0.0
    kind = FREE
    apex_t = np.full(apexes_wanted, np.nan)
    apex_h = np.full(apexes_wanted, np.nan)
    n_apex = 0
    ball_first = 0
    floor_first = 0
    start = np.zeros(2)
    contact_cap = 64 if record_contacts else 0
    contacts = np.empty((contact_cap, 3))
    n_contacts = 0
    phase_cap = 64 if record_phases else 0
    phases = np.empty((phase_cap, 6))
    n_phases = 0
    status = STATUS_PHASES
    for _ in range(MAX_PHASES):
        if record_phases:
            if n_phases == phase_cap:
                phase_cap *= 2
                grown = np.empty((phase_cap, 6))
                grown[:n_phases] = phases[:n_phases]
                phases = grown
            row = phases[n_phases]
            row[0], row[1], row[2], row[3], row[4], row[5] = t, kind, x1, x2, v1, v2
            n_phases += 1
        horizon = t_end - t
        horizon_event = EVENT_TIME
        if (kind & 2) == 0 and v2 > 0.0 and v2 < horizon:
            horizon = v2  # the upper ball flies freely: its apex is exactly v2 away
            horizon_event = EVENT_APEX
        event, tau, x1, x2, v1, v2 = advance_phase(
            kind,
            t,
            x1,
            x2,
            v1,
            v2,
            horizon,
            horizon_event,
            params,
            c0,
            c1,
            lam,
            vec,
            vec_inv,
            modal,
            a_both,
            y_rest,
        )
        t += tau
        if event in (EVENT_FLOOR, EVENT_BALL):
            bit = 1 << event
            if kind & bit:
                if record_contacts:
                    if n_contacts == contact_cap:
                        contact_cap *= 2
                        grown = np.empty((contact_cap, 3))
                        grown[:n_contacts] = contacts[:n_contacts]
                        contacts = grown
                    row = contacts[n_contacts]
                    row[0], row[1], row[2] = event, start[event], t
                    n_contacts += 1
            else:
                start[event] = t
                if n_apex == 0:
                    if event == EVENT_BALL:
                        ball_first += 1
                    else:
                        floor_first += 1
            kind ^= bit
        elif event == EVENT_APEX:
            v2 = 0.0
            apex_t[n_apex] = t
            apex_h[n_apex] = x2
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
        else:
            status = STATUS_STUCK
            break
    if record_contacts:
        # contacts still open at the end of the run end there
        for contact in range(2):
            if kind & (1 << contact):
                if n_contacts == contact_cap:
                    contact_cap *= 2
                    grown = np.empty((contact_cap, 3))
                    grown[:n_contacts] = contacts[:n_contacts]
                    contacts = grown
                row = contacts[n_contacts]
                row[0], row[1], row[2] = contact, start[contact], t
                n_contacts += 1
    return (
        status,
        t,
        apex_t,
        apex_h,
        n_apex,
        ball_first,
        floor_first,
        contacts[:n_contacts],
        phases[:n_phases],
        (x1, x2, v1, v2, float(kind)),
    )


@numba.njit(cache=True)
def sample(phases, times, params, c0, c1, lam, vec, vec_inv, modal, a_both, y_rest):
    """Exact state and forces at the given times from the recorded phases.

    Returns an array (len(times), 6): x1, x2, v1, v2, f01, f12.
    """
    z01, z12 = params[P_Z01], params[P_Z12]
    out = np.empty((times.size, 6))
    starts = phases[:, 0]
    for i in range(times.size):
        index = max(np.searchsorted(starts, times[i], side="right") - 1, 0)
        row = phases[index]
        kind = int(row[1])
        x1, x2, v1, v2, _, _ = state_at(
            kind,
            times[i] - row[0],
            row[2],
            row[3],
            row[4],
            row[5],
            params,
            lam,
            vec,
            vec_inv,
            modal,
            a_both,
            y_rest,
        )
        f01 = max(-(x1 + 2.0 * z01 * v1), 0.0) if kind & 1 else 0.0
        f12 = max(-((x2 - x1) + 2.0 * z12 * (v2 - v1)), 0.0) if kind & 2 else 0.0
        out[i, 0], out[i, 1], out[i, 2], out[i, 3], out[i, 4], out[i, 5] = x1, x2, v1, v2, f01, f12
    return out


def solve(drop: Drop, apexes: int, t_end: float, *, dense: bool | np.ndarray = False):
    """Run the exact solver on a validated drop; see :func:`twoball.simulate`.

    Returns (apex_t, apex_h, contacts rows, end time, status text or None, ball contacts before
    the first apex, floor contacts before it, sampled rows or None).
    """
    prepared = prepare(drop.mu, drop.zeta01, drop.zeta12)
    record_phases = dense is not False
    (status, end, apex_t, apex_h, n_apex, ball_first, floor_first, contacts, phases, _) = run(
        drop.x1_0, drop.x2_0, max(apexes, 1), t_end, *prepared, True, record_phases
    )
    samples = None
    if record_phases:
        times = default_times(phases, end) if dense is True else np.asarray(dense, dtype=float)
        samples = (
            times,
            sample(phases, times, *prepared),
        )
    return (
        list(apex_t[:n_apex]),
        list(apex_h[:n_apex]),
        contacts,
        end,
        STATUS_TEXT[status] or None,
        ball_first,
        floor_first,
        samples,
    )


def default_times(phases: np.ndarray, end: float, points: int = 2001) -> np.ndarray:
    """Plotting times: an even grid over the run plus 17 points inside every phase, so that
    brief contacts are drawn too."""
    starts = phases[:, 0]
    stops = np.append(starts[1:], end)
    inside = np.linspace(starts, stops, 17).ravel()
    return np.unique(np.concatenate([np.linspace(0.0, end, points), inside]))
