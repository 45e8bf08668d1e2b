"""What can go wrong in a run, by name: bad input, and how a run ended.

``ParameterError`` is the one exception for bad input (a ``ValueError``, so existing callers that
catch ``ValueError`` keep working); the command line reports it in one line with exit status 2,
and anything else keeps its traceback. ``Status`` is how a run ended, with the message a user
reads, in the manner of scipy's ``OdeResult.status``/``message``.
"""

from __future__ import annotations

from enum import IntEnum


class ParameterError(ValueError):
    """Bad input: the message names the parameter and its allowed range."""


class Status(IntEnum):
    """How a run ended. ``DONE`` and ``REST`` are successes; the others are not.

    ``STUCK`` and ``PHASE_LIMIT`` come from the exact solver (a bug or an input outside what
    double precision carries); ``FAILED`` and ``NO_APEX`` from the scipy references (an
    integrator error; no apex before the horizon, e.g. a ball at rest that the integrator cannot
    tell). The integer values are those the exact kernel returns and the sweep stores; printed,
    a status gives its name and message (``REST: the upper ball came to rest ...``), not its
    integer (``int(status)`` or ``f"{status:d}"`` give that).
    """

    DONE = 0
    REST = 1
    STUCK = 2
    PHASE_LIMIT = 3
    FAILED = 4
    NO_APEX = 5
    IMPOSSIBLE = 6

    def __str__(self) -> str:
        return f"{self.name}: {self.message}" if self.message else self.name

    def __format__(self, spec: str) -> str:
        return str(self) if not spec else int.__format__(self, spec)

    @property
    def message(self) -> str:
        """What happened, in words (empty for ``DONE``)."""
        return _MESSAGES[self]

    @property
    def success(self) -> bool:
        """True when the run reached what was asked or ended at rest, as the model says."""
        return self in (Status.DONE, Status.REST)


_MESSAGES = {
    Status.DONE: "",
    Status.REST: "the upper ball came to rest on the lower one",
    Status.STUCK: "root finder made no progress (please report: this is a bug)",
    Status.PHASE_LIMIT: "phase or step limit reached: the contacts did not settle within the "
    "solver's budget, so neither the apex asked for nor a rest was reached",
    Status.FAILED: "integrator failed",
    Status.NO_APEX: "no further apex before the integration horizon",
    Status.IMPOSSIBLE: "an apex that is not finite or above what the energy at release allows "
    "(the input is beyond what double precision resolves)",
}


def phase_limit_hint(floor_eps: float) -> str:
    """What is known about a run that reached the phase limit, for its message: an elastic
    floor (eps = 1) under a ball that never leaves it never settles; otherwise nothing more."""
    if floor_eps == 1.0:
        return " (the floor is elastic, eps = 1: a ball that never leaves it never settles)"
    return ""


class SolverError(RuntimeError):
    """A run that did not reach a trustworthy result (see ``simulate``'s ``throw``);
    ``result`` holds what was found, its ``status`` and ``reason`` say what happened."""

    def __init__(self, message: str, result=None) -> None:
        super().__init__(message)
        self.result = result
