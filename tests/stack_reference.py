"""An independent reference for stacks of N balls: scipy's DOP853, phase by phase, with events.

It shares nothing with twoball.stacks but the equations of docs/model.md, "Stacks of N balls":
inside a phase (a fixed set of active contacts) the right-hand side is smooth and integrated at
tight tolerances; a contact switch or the top ball's apex is an event. Steps are bounded by a
twentieth of the shortest contact period, so that no brief contact falls between two steps.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp


def reference_stack(
    masses: np.ndarray,
    zeta: np.ndarray,
    x_start: np.ndarray,
    apexes: int = 2,
    rtol: float = 1e-12,
    atol: float = 1e-10,
    t_max: float = 1e4,
) -> tuple[list[float], list[int]]:
    """The top ball's first ``apexes`` apex heights and, per contact, the contacts that start
    before the first apex."""
    n = len(masses)
    reduced = [masses[0]] + [
        masses[i - 1] * masses[i] / (masses[i - 1] + masses[i]) for i in range(1, n)
    ]
    max_step = min(2.0 * math.pi * math.sqrt(m) for m in reduced) / 20.0

    def overlaps(y):
        x, v = y[:n], y[n:]
        eta = np.concatenate([[x[0]], np.diff(x)])
        deta = np.concatenate([[v[0]], np.diff(v)])
        return eta, eta + 2.0 * zeta * deta

    active = np.zeros(n, dtype=bool)
    y = np.concatenate([x_start, np.zeros(n)])
    t = 0.0
    heights: list[float] = []
    first = [0] * n
    while len(heights) < apexes and t < t_max:
        on = active.copy()

        def rhs(_t, y, on=on):
            _, g = overlaps(y)
            f = np.where(on, -g, 0.0)
            above = np.append(f[1:], 0.0)
            return np.concatenate([y[n:], -1.0 + (f - above) / masses])

        events = []
        for c in range(n):
            if on[c]:  # the force -g falls to zero

                def ends(_t, y, c=c):
                    return overlaps(y)[1][c]

                ends.terminal, ends.direction = True, 1.0
                events.append(ends)
            else:  # max(eta, g) becomes negative

                def starts(_t, y, c=c):
                    eta, g = overlaps(y)
                    return max(eta[c], g[c])

                starts.terminal, starts.direction = True, -1.0
                events.append(starts)
        if not on[n - 1] and y[2 * n - 1] > 0.0:  # a free top ball going up

            def apex(_t, y):
                return y[2 * n - 1]

            apex.terminal, apex.direction = True, -1.0
            events.append(apex)
        solution = solve_ivp(
            rhs,
            (t, t_max),
            y,
            method="DOP853",
            rtol=rtol,
            atol=atol,
            events=events,
            max_step=max_step,
        )
        hit = [(e[0], k) for k, e in enumerate(solution.t_events) if len(e)]
        if not hit:
            break
        t, k = min(hit)
        y = solution.y_events[k][0].copy()
        if k == n:  # the apex
            heights.append(float(y[n - 1]))
            y[2 * n - 1] = 0.0
        else:
            active[k] = not active[k]
            if active[k] and not heights:
                first[k] += 1
    return heights, first
