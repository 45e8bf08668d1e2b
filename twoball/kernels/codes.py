"""The one vocabulary of the kernels: what ends a phase (events), how a run ends (statuses, the
integers of :class:`twoball.errors.Status`), the rounding unit of the certified steps and the
budgets of a run. The two-ball, the N-ball and the Hertz solvers all use these."""

from __future__ import annotations

from twoball.errors import Status
from twoball.model import MACHINE_EPSILON

# Events: what ends one phase. The two-ball kernel's switches name their contact (the floor's is
# contact 0, the balls' contact 1, as bit 0 and bit 1 of its phase kind); the N-ball kernels
# return EVENT_SWITCH with the contact beside it.
EVENT_FLOOR, EVENT_BALL = 0, 1
EVENT_APEX = 2  # a ball's apex in free flight
EVENT_TIME = 3  # the end of the run asked for
EVENT_REST = 4  # rest proven: no switch can happen again
EVENT_STUCK = 5  # the root finder made no progress
EVENT_STEPS = 6  # the step budget of a phase used up: a phase too long to finish, not a stall
EVENT_SWITCH = 7  # an N-ball contact switched on or off
EVENT_FAILED = 8  # an integrator could not go on (the Hertz reference's DOP853)

# How a run ends, as plain integers inside compiled code (twoball.errors.Status names them).
STATUS_DONE, STATUS_REST = int(Status.DONE), int(Status.REST)
STATUS_STUCK, STATUS_PHASES = int(Status.STUCK), int(Status.PHASE_LIMIT)
STATUS_FAILED = int(Status.FAILED)

ROUNDING = 16.0 * MACHINE_EPSILON  # tolerance in units of relative rounding
MAX_STEPS_PER_PHASE = 100_000
MAX_PHASES = 1_000_000
