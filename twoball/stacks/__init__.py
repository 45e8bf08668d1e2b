"""Stacks of N balls: the linear force solved exactly (:mod:`twoball.stacks.stack`), the Hertz
force (:mod:`twoball.stacks.hertz`), and what both share (:mod:`twoball.stacks.model`)."""

from twoball.stacks.model import (
    Stack,
    StackResult,
    StackTrajectory,
    check_stack,
    icm_chain,
    release_heights,
)
from twoball.stacks.stack import METHODS, simulate_stack

__all__ = [
    "METHODS",
    "Stack",
    "StackResult",
    "StackTrajectory",
    "check_stack",
    "icm_chain",
    "release_heights",
    "simulate_stack",
]
