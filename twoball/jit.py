"""How the kernels are compiled: numba's disk cache where it can be written, and the kernels'
own Python functions standing in for them while the compiler runs.

The kernels are the ``@njit`` functions of :mod:`twoball.model` and of :mod:`twoball.kernels`
(:data:`KERNEL_MODULES`). numba compiles them on first call (30-45 s
for the two-ball solver, about 2 minutes for the N-ball one, 30 s for the Hertz one, of one core
here) and
keeps the machine code on disk, beside the sources or in ``NUMBA_CACHE_DIR``. Two rules follow
from how programs are deployed:

- A cache that cannot be written never stops a program. The location is chosen once, before
  any kernel is declared: ``NUMBA_CACHE_DIR`` if it can be written; if it cannot (a prebuilt
  cache in a read-only image, or owned by another user), its contents are copied to a private
  directory under the temporary directory and that is used; without ``NUMBA_CACHE_DIR``, numba's
  default beside the sources, else ``~/.cache/twoball-numba``, else the temporary directory. If
  nothing can be written at all, the kernels compile in every process without a disk cache.
- A cache never serves machine code of older sources. numba checks only the timestamp of the
  file a kernel is defined in, but a kernel carries the code of every kernel it calls, and those of
  :mod:`twoball.kernels.stack` call :mod:`twoball.kernels.phases`'s. So the cache lives in a
  subdirectory named by a hash of all the kernel modules' sources (:func:`sources_key`): an edit to
  any of them starts a fresh cache. (Older subdirectories are left behind; delete them
  at will.)
- A program that cannot wait for the compiler (the app's first start) calls
  :func:`use_python_kernels`: every kernel is replaced by its pure-Python function (numba keeps
  it as ``py_func``; the calls between kernels follow, since they look each other up in their
  module). Same results, about 100 times slower. :func:`twoball.warmup.compile_in_background`
  compiles in a separate process, which fills the disk cache, and then switches back to the
  machine code.
"""

from __future__ import annotations

import hashlib
import importlib
import logging
import os
import shutil
import tempfile
import threading
from collections.abc import Callable, Iterable
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent
# the two-ball solver's kernel modules, then the N-ball stack's (compiled in that order on a
# first start: twoball.warmup.STAGES), each group holding the modules its kernels call
TWO_BALL_MODULES = (
    "twoball.model",
    "twoball.kernels.codes",
    "twoball.kernels.closed_forms",
    "twoball.kernels.phases",
    "twoball.kernels.runs",
)
STACK_MODULES = (
    "twoball.kernels.modes",
    "twoball.kernels.clusters",
    "twoball.kernels.stack",
    "twoball.kernels.taylor",
    "twoball.kernels.certified",
    "twoball.kernels.hertz",
)
KERNEL_MODULES = TWO_BALL_MODULES + STACK_MODULES

log = logging.getLogger(__name__)


def _writable(directory: Path) -> bool:
    """Whether files can be created in ``directory`` (made if missing), as numba needs."""
    try:
        directory.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=directory):
            return True
    except OSError:
        return False


def _private_directory() -> Path:
    return Path(tempfile.gettempdir()) / f"twoball-numba-{os.getuid()}"


def source_of(name: str) -> Path:
    """The source file of the kernel module ``name`` (twoball.kernels.codes: kernels/codes.py)."""
    return PACKAGE.joinpath(*name.split(".")[1:]).with_suffix(".py")


def sources_key() -> str:
    """A hash of the sources of every kernel module (:data:`KERNEL_MODULES`)."""
    digest = hashlib.sha256()
    for name in KERNEL_MODULES:
        digest.update(source_of(name).read_bytes())
    return digest.hexdigest()[:16]


def choose_cache_dir() -> Path | None | bool:
    """Where numba's cache goes: a directory, None for numba's default (``__pycache__`` beside
    the sources), or False when nothing can be written (no disk cache)."""
    configured = os.environ.get("NUMBA_CACHE_DIR")
    if configured:
        if _writable(Path(configured)):
            return Path(configured)
        private = _private_directory()
        if not _writable(private):
            return False
        if Path(configured).is_dir():  # a prebuilt cache we may read but not write: copy it
            shutil.copytree(configured, private, dirs_exist_ok=True)
        return private
    if _writable(PACKAGE / "__pycache__"):
        return None
    for candidate in (Path.home() / ".cache" / "twoball-numba", _private_directory()):
        if _writable(candidate):
            return candidate
    return False


_BASE = choose_cache_dir()
if _BASE is None:
    CACHE_DIR: Path | bool = PACKAGE / "__pycache__" / "numba" / sources_key()
elif _BASE is False or _BASE.name == sources_key():
    # already keyed: a process started by this one (compile_in_background) inherits
    # NUMBA_CACHE_DIR as set below and must fill the same directory, not one inside it
    CACHE_DIR = _BASE
else:
    CACHE_DIR = _BASE / sources_key()
CACHING = CACHE_DIR is not False

import numba  # noqa: E402 (after the cache directory is in the environment numba reads)
from numba.core import config as _numba_config  # noqa: E402
from numba.core.registry import CPUDispatcher  # noqa: E402

if isinstance(CACHE_DIR, Path):
    os.environ["NUMBA_CACHE_DIR"] = str(CACHE_DIR)
    _numba_config.CACHE_DIR = str(CACHE_DIR)


def compiled_on_disk(module: str) -> bool:
    """Whether the disk cache holds machine code of kernels of ``module`` (one of
    :data:`KERNEL_MODULES`) compiled from these sources: if not, their first call compiles."""
    if not isinstance(CACHE_DIR, Path):
        return False
    return any(CACHE_DIR.rglob(f"{source_of(module).stem}.*.nbi"))


def njit(
    function: Callable | None = None,
    *,
    nogil: bool = False,
    borrow: bool = False,
    inline: bool = False,
) -> Callable:
    """``numba.njit`` with the disk cache wherever one can be written (see the module);
    ``nogil`` releases the GIL while the compiled function runs (threads then run in parallel);
    ``borrow`` compiles it without numba's reference counts (``_nrt=False``): it may then
    allocate nothing, and the arrays handed to it are borrowed, not counted (numba increments
    and decrements the count of each array argument, atomically, on entry and exit); ``inline``
    inlines it into its callers in numba's own IR (a call handing it thirty arrays copies each
    one's descriptor; inlined into a caller compiled with ``borrow``, nothing is counted either)."""
    if function is None:
        return lambda wrapped: njit(wrapped, nogil=nogil, borrow=borrow, inline=inline)
    options = {"inline": "always"} if inline else {}
    if borrow:
        options["_nrt"] = False
    return numba.njit(cache=CACHING, nogil=nogil, **options)(function)


_dispatchers: dict[str, dict[str, CPUDispatcher]] = {}
_lock = threading.Lock()
state = "compiled"  # or "python" while the kernels' Python functions stand in, or "compiling"
# the kernel modules whose Python functions stand in for their kernels (use_python_kernels),
# until use_compiled_kernels puts their machine code back
python_modules: set[str] = set()


def compiled(module: str) -> bool:
    """Whether the kernels of ``module`` (one of :data:`KERNEL_MODULES`) run as machine code."""
    return module not in python_modules


def use_python_kernels() -> None:
    """Run every kernel as its pure-Python function from now on (same results, ~100x slower)."""
    global state
    with _lock:
        # every kernel module imported before any is swapped: one first imported midway took
        # the Python stand-in of a kernel it imports from a module already swapped (hertz's
        # ``force_bounds``), never saved and never put back, and the compiler then failed on
        # it ("Untyped global name"): a first start with a cold cache stayed on Python kernels
        modules = {name: importlib.import_module(name) for name in KERNEL_MODULES}
        for name, module in modules.items():
            saved = _dispatchers.setdefault(name, {})
            for attribute, value in vars(module).items():
                if isinstance(value, CPUDispatcher):
                    saved[attribute] = value
            for attribute, dispatcher in saved.items():
                setattr(module, attribute, dispatcher.py_func)
        python_modules.update(modules)
        state = "python"


def use_compiled_kernels(modules: Iterable[str] | None = None) -> None:
    """Put the compiled kernels of ``modules`` back, all by default (they load from the disk
    cache, or compile, on first call).

    ``modules`` must hold every kernel module whose kernels theirs import (or those must be
    back already): a kernel compiled while a kernel it calls is a Python stand-in fails
    ("Untyped global name"). A Python stand-in keeps calling stand-ins, its module's names, until
    its own module is put back."""
    global state
    with _lock:
        names = list(_dispatchers) if modules is None else list(modules)
        for name in names:
            module = importlib.import_module(name)
            for attribute, dispatcher in _dispatchers.get(name, {}).items():
                setattr(module, attribute, dispatcher)
            python_modules.discard(name)
        if not python_modules:
            state = "compiled"
