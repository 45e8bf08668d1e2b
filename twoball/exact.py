"""The exact solver's Python side: a validated drop run by the compiled two-ball kernel
(:mod:`twoball.kernels.runs`; the method, and why no contact can be missed, in
:mod:`twoball.kernels.phases`), its outcome handed on as an :class:`~twoball.observables.Outcome`.
"""

from __future__ import annotations

import numpy as np

from twoball.errors import ParameterError, Status

# by module, not by name: jit.use_python_kernels swaps the kernels in their own modules
from twoball.kernels import runs
from twoball.kernels.phases import Prepared
from twoball.model import Drop
from twoball.observables import Outcome, RunStats


class ExactDense:
    """The exact state at any times from a run's recorded phases
    (:func:`twoball.kernels.runs.sample`): arrays only, so that a result with dense output
    pickles (a closure would not)."""

    def __init__(self, phases: np.ndarray, prepared: Prepared) -> None:
        self.phases = phases
        self.prepared = prepared

    def __call__(self, times: np.ndarray, side: str = "right") -> np.ndarray:
        """Rows x1, x2, v1, v2, f01, f12 at ``times``; at a switch the side of it asked for."""
        times = np.asarray(times, dtype=float)
        return runs.sample(self.phases, times, self.prepared, side == "left")


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
        out = runs.run_drop(
            drop.mu, drop.zeta01, drop.zeta12, drop.x1_0, drop.x2_0, max(apexes, 1), t_end
        )
    else:
        prepared = runs.prepare(drop.mu, drop.zeta01, drop.zeta12)
        out = runs.run(drop.x1_0, drop.x2_0, max(apexes, 1), t_end, prepared, True, True)
        evaluate = ExactDense(out.phases, prepared)
        plot_times = default_times(out.phases, out.end_time)
    status = Status(out.status)
    return Outcome(
        apex_t=out.apex_t.tolist(),
        apex_h=out.apex_h.tolist(),
        contacts=out.contacts,
        end_time=out.end_time,
        status=status,
        message=status.message or None,
        contacts_first=[out.floor_contacts_first, out.ball_contacts_first],
        evaluate=evaluate,
        plot_times=plot_times,
        stats=RunStats(out.phase_count, out.step_count, out.root_count),
    )


def default_times(phases: np.ndarray, end: float, points: int = 2001) -> np.ndarray:
    """Plotting times: an even grid over the run plus 17 points inside every phase, so that
    brief contacts are drawn too."""
    starts = phases[:, 0]
    stops = np.append(starts[1:], end)
    inside = np.linspace(starts, stops, 17).ravel()
    return np.unique(np.concatenate([np.linspace(0.0, end, points), inside]))
