"""twoball: the two-ball bounce solved exactly (see docs/model.md and the README)."""

from twoball.batch.cubes import load_cube
from twoball.errors import ParameterError, Status
from twoball.model import Parameters, check_parameters
from twoball.observables import ContactInterval, Result, Trajectory
from twoball.solve import METHODS, SolverError, simulate
from twoball.stacks import Stack, StackResult, icm_chain, simulate_stack
from twoball.version import __version__

__all__ = [
    "METHODS",
    "ContactInterval",
    "ParameterError",
    "Parameters",
    "Result",
    "SolverError",
    "Stack",
    "StackResult",
    "Status",
    "Trajectory",
    "__version__",
    "check_parameters",
    "load_cube",
    "icm_chain",
    "simulate",
    "simulate_stack",
]
