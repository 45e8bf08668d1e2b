"""Every kernel compiled before it is needed: :func:`warm_up` calls each kernel path once (the
Dockerfile runs it), and :func:`compile_in_background` lets a program that cannot wait
(the app's first start) run on the kernels' Python functions while another process compiles them
(:mod:`twoball.jit` has the disk cache and the switch between the two)."""

from __future__ import annotations

import contextlib
import logging
import subprocess
import sys
import tempfile
import threading
from collections.abc import Callable

from twoball import jit

log = logging.getLogger(__name__)


def warm_up_two_ball() -> None:
    """Call the two-ball solver's kernel paths once: a drop to its second apex for its heights
    only (twoball.kernels.runs.run_drop) and with its trajectory sampled (runs.run and
    runs.sample), and the batch path of sweeps and the map (runs.run_block). Each path left out
    was compiled by the first page to take it, in the server, after this stage: one page then
    waited 10.8 s (benchmarks/first_start.py)."""
    from twoball.batch.sweep import compute_block
    from twoball.solve import simulate

    simulate(0.9, 0.01, 0.01, until="second")
    simulate(0.9, 0.01, 0.01, until="second", t_eval=[0.0, 1.0])
    compute_block([0.9], [0.01], [0.01])


def warm_up_stacks() -> None:
    """Call the N-ball solver's kernel paths once (twoball.kernels.stack), then the Hertz
    force's (twoball.kernels.hertz): each sampled at given times, and kept whole and evaluated
    afterwards, as the app's Stack scene does (the Hertz force's cubics between its steps,
    hertz.between_nodes, were otherwise compiled by the first page to draw a Hertz stack)."""
    from twoball.stacks import simulate_stack

    for force in ("linear", "hertz"):
        simulate_stack([0.2, 0.2], 0.9, 0.2, force=force, t_eval=[0.0, 1.0])
        simulate_stack([0.2, 0.2], 0.9, 0.2, force=force, dense_output=True).evaluate([0.0, 1.0])


# The kernels compiled in two stages, the two-ball solver's first: what a page opens on, 30-45 s
# of the ~3 minutes it all takes (a stack's solver ~2 minutes). Each stage: its name, its kernel
# modules, and the function that calls their kernel paths. A stage's modules hold every kernel
# module whose kernels theirs import, with the stages before it (jit.use_compiled_kernels;
# tests/test_packaging.py checks it).
STAGES: tuple[tuple[str, tuple[str, ...], Callable[[], None]], ...] = (
    ("two-ball", jit.TWO_BALL_MODULES, warm_up_two_ball),
    ("stacks", jit.STACK_MODULES, warm_up_stacks),
)


def in_use(stage: str) -> bool:
    """Whether the kernels of ``stage`` (a name in :data:`STAGES`) run as machine code."""
    modules = next(modules for name, modules, _ in STAGES if name == stage)
    return all(jit.compiled(module) for module in modules)


def warm_up(report: bool = False, lock: str | None = None) -> None:
    """Call every kernel path once, stage by stage (:data:`STAGES`); ``report``: print each
    stage's name once its kernels are compiled (the compiler process of
    :func:`compile_in_background` tells its server so); ``lock``: a file locked while each
    stage compiles, so that one compiler at a time works on a cache."""
    for name, _, call in STAGES:
        with open(lock, "w") if lock else contextlib.nullcontext() as held:
            if held is not None:
                import fcntl  # (POSIX: where a server compiles in another process)

                fcntl.flock(held, fcntl.LOCK_EX)  # (released as the file closes)
            call()
        if report:
            print(name, flush=True)


def compile_in_background(
    done: Callable[[], None] | None = None, staged: Callable[[str], None] | None = None
) -> threading.Thread:
    """Stand the Python functions in for the kernels now; compile them in another process
    (which fills the disk cache) and put each stage's machine code back (:data:`STAGES`) as
    soon as that process has compiled it: the two-ball solver's in 30-45 s, not after the
    stacks' 2 minutes more.

    Without a disk cache the other process cannot help: the kernels then compile in this
    process's thread, stage by stage, under the lock that numba takes.
    ``staged`` is called with each stage's name once its kernels are in use, ``done`` once
    all are.
    """
    jit.use_python_kernels()

    def put_back(name: str, modules: tuple[str, ...], call: Callable[[], None]) -> None:
        jit.use_compiled_kernels(modules)
        call()  # loads the machine code from the cache (or compiles it here)
        if staged is not None:
            staged(name)

    def work() -> None:
        jit.state = "compiling"
        stages = {name: (name, modules, call) for name, modules, call in STAGES}
        if jit.CACHING:
            # niced: the pages being served come first; one compiler at a time per cache and
            # stage (the processes of `twoball serve --num-procs N` start together: the others
            # wait on the lock without using a core, then find the stage in the cache; locked
            # for the whole compile, they got the two-ball solver only with the stacks, at
            # 290 s, not 104); it prints each stage's name when done (its errors go to a
            # file: a full pipe would stop it)
            lock = jit.CACHE_DIR / "compiling.lock"
            script = (
                "import os; os.nice(10); from twoball import warmup; "
                f"warmup.warm_up(report=True, lock={str(lock)!r})"
            )
            with tempfile.TemporaryFile("w+") as errors:
                compiler = subprocess.Popen(
                    [sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=errors, text=True
                )
                for line in compiler.stdout:
                    if line.strip() in stages:
                        put_back(*stages.pop(line.strip()))
                if compiler.wait() != 0:
                    errors.seek(0)
                    log.warning("compiling the kernels failed: %s", errors.read().strip()[-2000:])
        for stage in stages.values():  # (those the other process did not compile, if any)
            put_back(*stage)
        jit.use_compiled_kernels()
        if done is not None:
            done()

    thread = threading.Thread(target=work, name="twoball-compile", daemon=True)
    thread.start()
    return thread
