"""Local worker processes, one helper for the sweep and the studies.

Workers are started with "spawn": nothing is inherited, so the function they run must be
importable by name (a module-level function), and each worker loads the compiled kernels once
before its first task (a time cap then counts only the task). A task over the cap kills its
worker, which is replaced. A worker exits by itself when the process that started it is gone,
even after kill -9 (its pipe closes), so a killed sweep leaves no orphans.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import time
from collections.abc import Callable, Iterator, Sequence
from typing import Any


def _serve(connection, function: Callable[..., Any]) -> None:
    from twoball.solve import simulate

    simulate(0.8, 0.1, 0.5)  # load the compiled kernel before any timing
    connection.send("ready")
    while True:
        try:
            task = connection.recv()
        except (EOFError, OSError):  # the parent is gone
            return
        if task is None:
            return
        result = function(*task)
        try:
            connection.send(result)
        except (BrokenPipeError, OSError):  # the parent went while this task ran
            return


class Workers:
    """``count`` processes running ``function(*task)``; use as a context manager.

    Parameters
    ----------
    count : int
        Number of processes.
    function : callable
        A module-level function (it is imported by name in the workers).
    cap : float, optional
        Seconds a task may take; a task over it kills its worker, which is replaced, and its
        result is ``None`` (as is that of a task whose worker died). No cap by default.
    """

    def __init__(self, count: int, function: Callable[..., Any], cap: float | None = None):
        self.context = multiprocessing.get_context("spawn")
        self.cap = cap
        self.function = function
        self.slots = [self._start() for _ in range(count)]

    def _start(self):
        parent, child = self.context.Pipe()
        process = self.context.Process(target=_serve, args=(child, self.function), daemon=True)
        process.start()
        child.close()  # the worker holds the only other end: its death closes the pipe
        parent.recv()  # started and warmed up: the cap counts from the first task
        return process, parent

    def results(self, tasks: Sequence[tuple]) -> Iterator[tuple[int, Any, float]]:
        """(task index, result, seconds) for every task, in the order they finish; the result of
        a task killed over the cap, or whose worker died, is ``None``."""
        pending = list(enumerate(tasks))
        busy: dict[int, tuple[int, float]] = {}  # slot -> (task index, start time)
        while pending or busy:
            for slot in range(len(self.slots)):
                if slot not in busy and pending:
                    index, task = pending.pop(0)
                    self.slots[slot][1].send(task)
                    busy[slot] = (index, time.monotonic())
            for slot, (index, started) in list(busy.items()):
                process, connection = self.slots[slot]
                if connection.poll(0.01):
                    result = connection.recv()
                elif not process.is_alive() or (
                    self.cap is not None and time.monotonic() - started > self.cap
                ):
                    process.kill()
                    process.join()
                    self.slots[slot] = self._start()
                    result = None
                else:
                    continue
                del busy[slot]
                yield index, result, time.monotonic() - started

    def close(self) -> None:
        """Stop every worker (a worker that does not stop within 5 s is killed)."""
        for process, connection in self.slots:
            with contextlib.suppress(BrokenPipeError, OSError):
                connection.send(None)
            process.join(timeout=5)
            if process.is_alive():
                process.kill()

    def __enter__(self) -> Workers:
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()
