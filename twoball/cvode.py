"""SUNDIALS CVODE (through scikit-sundae) as a reference method: the strongest general peer.

The same equations, switching functions and measurements as :mod:`twoball.reference`
(docs/model.md, "Bodies, coordinates, forces" and "What is measured"): CVODE's root finding
watches the two contacts' switching functions max(eta, g) and the upper ball's velocity; the
integration restarts from the located state at every root, so the multistep history never spans
a kink of the right-hand side. BDF with the analytic Jacobian (the contact phases are stiff for
small mu). Like every adaptive method with event location it can step over a contact that
begins and ends inside one step and then silently let the balls pass through each other
(docs/accuracy.md says where).

Optional: needs the ``cvode`` extra (``pip install 'twoball[cvode]'``); without it ``solve``
raises ModuleNotFoundError naming scikit-sundae (the command line names the extra).
"""

from __future__ import annotations

import contextlib
import io
import os
from collections.abc import Iterator

import numpy as np

from twoball.errors import ParameterError
from twoball.model import Drop
from twoball.observables import Outcome
from twoball.reference import _right_hand_side, forces, outcome_from_events, time_limit

MAX_STEPS = 1_000_000
MAX_RESTARTS = 100_000
# SUNDIALS' logger writes its errors to C's stderr and its warnings (such as "t + h = t on the
# next step") to C's stdout, or to the files these variables name, read as each run begins
# (SUNDIALS' documentation, "Status and Error Logging").
SUNDIALS_LOG_VARIABLES = ("SUNLOGGER_ERROR_FILENAME", "SUNLOGGER_WARNING_FILENAME")


def solve(
    drop: Drop, apexes: int, t_end: float, *, rtol: float, atol: float, dense_output: bool = False
) -> Outcome:
    """Integrate with CVODE (BDF) to the wanted apexes; an Outcome like
    :func:`twoball.reference.solve`'s, without dense output."""
    if dense_output:
        raise ParameterError("CVODE gives no dense output here (t_eval, dense_output)")
    from sksundae.cvode import CVODE

    rhs_list, jacobian = _right_hand_side(drop)
    z01, z12 = drop.zeta01, drop.zeta12
    touching = 1e-12 * (1.0 + drop.x2_0)  # as in reference: eta == 0 at a touching release

    def rhs(t, y, yp):
        yp[:] = rhs_list(t, y)

    def jac(t, y, yp, jj):
        jj[:, :] = jacobian(t, y)

    def roots(t, y, out):
        eta = y[1] - y[0]
        out[0] = max(y[0], y[0] + 2.0 * z01 * y[2])
        out[1] = max(eta, eta + 2.0 * z12 * (y[3] - y[2])) + touching
        out[2] = y[3] - 1e-12

    roots.terminal = [True, True, True]
    roots.direction = [0, 0, -1]
    horizon = min(t_end, time_limit(drop, apexes))
    t0, y0 = 0.0, np.array([drop.x1_0, drop.x2_0, 0.0, 0.0])
    apex_t: list[float] = []
    apex_h: list[float] = []
    events: tuple[list, list] = ([], [])
    failure = None
    with _quiet_sundials() as printed:
        for _ in range(MAX_RESTARTS):
            if len(apex_t) >= apexes or t0 >= horizon:
                break
            solver = CVODE(
                rhs,
                method="BDF",
                rtol=rtol,
                atol=atol,
                jacfn=jac,
                eventsfn=roots,
                num_events=3,
                max_num_steps=MAX_STEPS,
            )
            sol = solver.solve(np.array([t0, horizon]), y0)
            if not sol.success:
                # what scikit-sundae's error handler printed, such as "At t = 0, too much
                # accuracy requested.", completes its message
                said = " ".join(printed.getvalue().split())
                failure = f"CVODE failed: {sol.message}" + (f" ({said})" if said else "")
                break
            if sol.t_events is None or sol.t_events.size == 0:
                t0 = horizon
                break
            t0, y0 = float(sol.t_events[-1]), sol.y_events[-1].copy()
            which = sol.i_events[-1]
            for contact in (0, 1):
                if which[contact] != 0:
                    events[contact].append((t0, y0.copy()))
            if which[2] != 0:
                _, f12 = forces(y0, z01, z12)
                if f12 == 0.0:
                    apex_t.append(t0)
                    apex_h.append(float(y0[1]))
                y0[3] = min(y0[3], 0.0)  # below the root's zero, so it does not fire again at once
        else:
            failure = "CVODE: restart limit reached"
    return outcome_from_events(drop, apex_t, apex_h, events, t0, apexes, t_end, horizon, failure)


@contextlib.contextmanager
def _quiet_sundials() -> Iterator[io.StringIO]:
    """Keep CVODE's own printing off the terminal (a failure is the Outcome's reason): SUNDIALS'
    logger writes to the null device (unless the user named its files) and scikit-sundae's
    error handler, which prints with Python's print, into the StringIO yielded. Both settings
    are the process's, undone when the run ends."""
    unset = [name for name in SUNDIALS_LOG_VARIABLES if name not in os.environ]
    for name in unset:
        os.environ[name] = os.devnull
    try:
        with contextlib.redirect_stdout(io.StringIO()) as printed:
            yield printed
    finally:
        for name in unset:
            os.environ.pop(name, None)
