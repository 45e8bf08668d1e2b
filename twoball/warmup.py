"""Every kernel compiled before it is needed: :func:`warm_up` calls each kernel path once (the
Dockerfile runs :data:`WARM_UP`), and :func:`compile_in_background` lets a program that cannot wait
(the app's first start) run on the kernels' Python functions while another process compiles them
(:mod:`twoball.jit` has the disk cache and the switch between the two)."""

from __future__ import annotations

import logging
import subprocess
import sys
import threading
from collections.abc import Callable

from twoball import jit

# what compiles every kernel in a new process (the Dockerfile runs it too)
WARM_UP = "from twoball import warmup; warmup.warm_up()"

log = logging.getLogger(__name__)


def warm_up() -> None:
    """Call every kernel path once (a drop to its second apex with a sampled trajectory)."""
    from twoball.solve import simulate

    simulate(0.9, 0.01, 0.01, until="second", dense_output=True)
    from twoball.batch.sweep import compute_block  # the batch path (twoball.kernels.runs.run_block)

    compute_block([0.9], [0.01], [0.01])
    from twoball.stacks import simulate_stack  # the N-ball solver (twoball.kernels.stack)

    simulate_stack([0.2, 0.2], 0.9, 0.2, t_eval=[0.0, 1.0])
    # the Hertz stack (twoball.kernels.hertz)
    simulate_stack([0.2, 0.2], 0.9, 0.2, force="hertz", t_eval=[0.0, 1.0])


def compile_in_background(done: Callable[[], None] | None = None) -> threading.Thread:
    """Stand the Python functions in for the kernels now; compile them in another process
    (:data:`WARM_UP`, which fills the disk cache) and switch back when it is done.

    Without a disk cache the other process cannot help: the kernels then compile in this
    process's thread, under the lock that numba takes, and the switch comes after that.
    ``done`` is called once the compiled kernels are in use.
    """
    jit.use_python_kernels()

    def work() -> None:
        jit.state = "compiling"
        if jit.CACHING:
            # niced: the pages being served come first; one compiler at a time per cache (the
            # processes of `twoball serve --num-procs N` start together: the others wait on
            # the lock without using a core, then find the cache filled)
            lock = jit.CACHE_DIR / "compiling.lock"
            script = (
                f"import fcntl, os; os.nice(10); lock = open({str(lock)!r}, 'w'); "
                f"fcntl.flock(lock, fcntl.LOCK_EX); {WARM_UP}"
            )
            outcome = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
            if outcome.returncode != 0:
                log.warning("compiling the kernels failed: %s", outcome.stderr.strip()[-2000:])
        jit.use_compiled_kernels()
        warm_up()  # loads the machine code from the cache (or compiles it here)
        if done is not None:
            done()

    thread = threading.Thread(target=work, name="twoball-compile", daemon=True)
    thread.start()
    return thread
