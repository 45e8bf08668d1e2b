"""Sweeps: the bounces over a grid of (eps, mu, tau_ratio), stored as a resumable Zarr cube.

The grid is cut into chunks; each chunk is computed by the exact solver (docs/model.md, "What is
measured"), calling its compiled kernel case by case for the apex heights and times and the
contact count only (no contact intervals, no phases are recorded). Chunks run in parallel
(local threads, each writing its own chunks, or a Dask distributed cluster whose results this
process writes) and each is written to the store as soon as it finishes, then marked done.

Why Zarr (v3): every chunk is its own file, written independently; a reader takes one slice by
reading only the chunks it touches, and a run that was killed restarts by skipping the chunks
whose done-marker exists. A chunk that was being written when the run died has no marker and is
simply computed and written again, so the finished cube is the same as an uninterrupted run's.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import sys
from concurrent.futures import ThreadPoolExecutor
from concurrent.futures import as_completed as threads_completed
from dataclasses import asdict, dataclass, field
from fractions import Fraction
from itertools import product
from pathlib import Path

import numpy as np

from twoball.errors import ParameterError
from twoball.kernels import runs
from twoball.kernels.codes import STATUS_DONE, STATUS_PHASES, STATUS_REST, STATUS_STUCK
from twoball.model import (
    DEFAULT_HEIGHT,
    check_parameters,
    check_value,
    damping_ratios,
    decay_ratio,
    floor_contact_time,
    icm_height,
    initial_gap_height,
)
from twoball.observables import ratios

DIMS = ("eps", "mu", "tau_ratio")
FORCES = ("linear", "hertz")  # the hertz force's cells: twoball/batch/hertz_sweep.py
SPACINGS = ("linear", "log")
DTYPES = ("float64", "float32")
SOLVER = "exact"
SCHEDULER_TIMEOUT = "10s"  # to connect to a Dask scheduler
PROGRESS_DIR = "_progress"  # a Zarr group holding one empty file per finished chunk
# Drops a sweep undertakes without --force: over an hour on 2 cores at the rate below.
MAX_DROPS = 100_000_000
# The same with the Hertz force (about an hour on 2 cores at its rate,
# twoball/batch/hertz_sweep.py); here, not there, so that the command line's help needs no Hertz
# kernel (nor scipy) to start.
MAX_HERTZ_DROPS = 4_000_000
# Drops per second one local thread computes, end to end, for the plan's estimate: cautious (the
# paper's 50^3 cube runs at 40 000-150 000/s on 2 threads depending on the machine's load,
# docs/performance.md; heavier corners of the domain take longer per drop).
DROPS_PER_WORKER_SECOND = 11_000

HEIGHT_UNITS = "m1 g / k (dimensionless height X = z k / (m1 g))"
TIME_UNITS = "sqrt(m1 / k) (dimensionless time tau)"

# name: (units, long_name); every data variable of a cube, in this order. contacts_first is the
# ball-ball count only (a Result's contacts_first[1]), whole numbers kept in the floating type of
# the other variables so that NaN marks a drop without a first apex, as in h1 and t1:
# CONTACTS_DESCRIPTION says so in the variable's attributes.
VARIABLES = {
    "h1": (HEIGHT_UNITS, "first apex height X2 of the upper ball in free flight"),
    "h2": (HEIGHT_UNITS, "second apex height X2 of the upper ball (NaN: no second apex)"),
    "t1": (TIME_UNITS, "time of the first apex"),
    "t2": (TIME_UNITS, "time of the second apex (NaN: no second apex)"),
    "contacts_first": ("1", "ball-ball contacts before the first apex (Result.contacts_first[1])"),
    "h_icm": (HEIGHT_UNITS, "first apex in the independent contact model (h_ICM)"),
    "x2_0": (HEIGHT_UNITS, "initial height X2(0) of the upper ball"),
    "h1_over_icm": ("1", "h1 / h_ICM"),
    "h1_over_drop": ("1", "h1 / X2(0)"),
    "h2_over_drop": ("1", "h2 / X2(0)"),
    "h2_over_h1": ("1", "h2 / h1"),
    "delayed_rebound": ("1", "delayed rebound: h2 > h1 (False where h2 does not exist)"),
    "status": ("1", "how the run ended"),
}
CONTACTS_DESCRIPTION = (
    "Number of separate contact intervals of the two balls (contact 1) before the upper "
    "ball's first apex: the paper's count, a Result's contacts_first[1]. The floor's contacts "
    "(Result.contacts_first[0]) are not stored. Whole numbers, stored as floating point so "
    "that NaN can mark a drop without a first apex (status says how it ended)."
)
STATUS_FLAGS = {
    STATUS_DONE: "second_apex_reached",
    STATUS_REST: "upper_ball_came_to_rest",
    STATUS_STUCK: "root_finder_stuck",
    STATUS_PHASES: "phase_limit_reached",
}
COORDINATES = {
    "eps": "coefficient of restitution eps (floor; also ball-ball unless eps12 is set)",
    "mu": "mass ratio mu = m2 / m1",
    "tau_ratio": "tau_d / tau_f: delay of the upper ball over the floor contact time",
}


# Drops in a default chunk: about a tenth of a second of compute, so that a sweep has chunks
# enough for its threads and to resume from, and few enough files: one eps value a chunk (650
# files for the paper's cube) spent as much CPU in Zarr's writes as the kernel did; five (the
# paper's cube, 50 x 50 planes) ran it at 141 000 cases/s against 86 000 (2 cores, idle).
CHUNK_DROPS = 12_500


@dataclass(frozen=True)
class Axis:
    """One axis of a sweep grid: ``count`` values from ``start`` to ``stop`` (both included)."""

    name: str
    start: float
    stop: float
    count: int
    spacing: str = "linear"

    def __post_init__(self) -> None:
        if self.name not in DIMS:
            raise ParameterError(f"axis must be one of {', '.join(DIMS)}; got {self.name!r}")
        check_value(self.name, self.start)
        check_value(self.name, self.stop)
        if not isinstance(self.count, int) or self.count < 1:
            raise ParameterError(f"{self.name}: count must be an integer >= 1; got {self.count!r}")
        if self.spacing not in SPACINGS:
            raise ParameterError(
                f"{self.name}: spacing must be linear or log; got {self.spacing!r}"
            )
        if self.spacing == "log" and self.start <= 0.0:
            raise ParameterError(f"{self.name}: a log axis needs start > 0; got {self.start!r}")
        if self.count == 1 and self.stop != self.start:
            raise ParameterError(f"{self.name}: one value needs start == stop")
        if self.count > 1 and not self.stop > self.start:
            raise ParameterError(f"{self.name}: stop must be greater than start")

    def values(self) -> np.ndarray:
        """The grid values, end points exactly as given."""
        if self.count == 1:
            return np.array([self.start])
        if self.spacing == "log":
            return np.geomspace(self.start, self.stop, self.count)
        return np.linspace(self.start, self.stop, self.count)

    def text(self) -> str:
        """The command-line form START:STOP:COUNT:SPACING (see :func:`parse_axis`)."""
        return f"{self.start!r}:{self.stop!r}:{self.count}:{self.spacing}"


def parse_axis(name: str, text: str) -> Axis:
    """An axis of a sweep from its command-line text.

    Parameters
    ----------
    name : str
        The axis: "eps", "mu" or "tau_ratio".
    text : str
        ``VALUE`` (one point) or ``START:STOP:COUNT[:linear|log]``, end points included;
        fractions such as 1/3 are allowed.

    Returns
    -------
    Axis

    Raises
    ------
    ParameterError
        Naming the axis and what is wrong with the text.

    Examples
    --------
    >>> from twoball.batch.sweep import parse_axis
    >>> parse_axis("mu", "0.01:1/3:3").values().round(4).tolist()
    [0.01, 0.1717, 0.3333]
    >>> parse_axis("eps", "0.5:1:3:log").spacing
    'log'
    """
    parts = text.split(":")
    if len(parts) == 1:
        value = _parse_number(name, parts[0])
        return Axis(name, value, value, 1)
    if len(parts) not in (3, 4):
        raise ParameterError(f"{name} must be VALUE or START:STOP:COUNT[:linear|log]; got {text!r}")
    try:
        count = int(parts[2])
    except ValueError:
        raise ParameterError(f"{name}: COUNT must be an integer; got {parts[2]!r}") from None
    spacing = parts[3] if len(parts) == 4 else "linear"
    start, stop = _parse_number(name, parts[0]), _parse_number(name, parts[1])
    return Axis(name, start, stop, count, spacing)


def parse_number(text: str) -> float:
    """A number written as a float or a fraction such as 1/3 (the command line's numbers);
    ValueError saying so otherwise."""
    try:
        return float(Fraction(text.strip())) if "/" in text else float(text)
    except (ValueError, ZeroDivisionError):
        raise ValueError(f"not a number: {text!r}") from None


def _parse_number(name: str, text: str) -> float:
    try:
        return parse_number(text)
    except ValueError as error:
        raise ParameterError(f"{name}: {error}") from None


@dataclass(frozen=True)
class Grid:
    """What a sweep computes.

    Parameters
    ----------
    eps, mu, tau_ratio : Axis
        The three axes (see :func:`parse_axis`).
    height : float
        The drop height H of every drop (1e4).
    eps12 : float or None
        The ball-ball restitution of every drop; None makes it equal to eps.
    chunks : (int, int, int) or None
        Storage chunks along (eps, mu, tau_ratio); None stores whole (mu, tau_ratio) planes,
        as many eps values a chunk as make about CHUNK_DROPS drops (at least one).
    dtype : "float64" or "float32"
        The stored float type.
    force : "linear" or "hertz"
        The contact force: the linear one, solved exactly, or Hertz's (two balls, the compiled
        Hertz path, :mod:`twoball.batch.hertz_sweep`; H then in Hertz units, and the corners are
        checked against the Hertz domain).

    Examples
    --------
    >>> from twoball.batch.sweep import Grid, parse_axis
    >>> grid = Grid(parse_axis("eps", "0.9"), parse_axis("mu", "0.01:0.1:2"),
    ...             parse_axis("tau_ratio", "0.01:1:5:log"))
    >>> grid.shape, grid.size
    ((1, 2, 5), 10)
    """

    eps: Axis
    mu: Axis
    tau_ratio: Axis
    height: float = DEFAULT_HEIGHT
    eps12: float | None = None
    chunks: tuple[int, int, int] | None = None
    dtype: str = "float64"
    force: str = "linear"
    axes: tuple[Axis, Axis, Axis] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "axes", (self.eps, self.mu, self.tau_ratio))
        for axis, dim in zip(self.axes, DIMS, strict=True):
            if axis.name != dim:
                raise ParameterError(f"the {dim} axis is named {axis.name!r}")
        check_value("height", self.height)
        if self.eps12 is not None:
            check_value("eps12", self.eps12)
        if self.force not in FORCES:
            raise ParameterError(f"force must be linear or hertz; got {self.force!r}")
        if self.dtype not in DTYPES:
            raise ParameterError(f"dtype must be float64 or float32; got {self.dtype!r}")
        if self.chunks is None:
            plane = self.mu.count * self.tau_ratio.count
            drops = CHUNK_DROPS if self.force == "linear" else _hertz().CHUNK_DROPS
            slices = min(max(round(drops / plane), 1), self.eps.count)
            object.__setattr__(self, "chunks", (slices, self.mu.count, self.tau_ratio.count))
        chunks = tuple(self.chunks)
        if len(chunks) != 3 or not all(isinstance(c, int) and c >= 1 for c in chunks):
            raise ParameterError(f"chunks must be three integers >= 1; got {self.chunks!r}")
        object.__setattr__(self, "chunks", chunks)
        if self.force == "hertz":  # the Hertz domain, at the corners too (hertz_sweep)
            corners = [(a.start, a.stop) for a in self.axes]
            _hertz().check_corners(*corners, self.height, self.eps12)
            return
        # every drop must lie in the domain double precision carries; its rounding ratio is
        # monotone along each axis, so the grid's corners decide (docs/model.md)
        for eps, mu, tau_ratio in product(*((a.start, a.stop) for a in self.axes)):
            check_parameters(eps, mu, tau_ratio, eps12=self.eps12, height=self.height)

    @property
    def shape(self) -> tuple[int, int, int]:
        return tuple(axis.count for axis in self.axes)

    @property
    def size(self) -> int:
        return math.prod(self.shape)

    def chunk_slices(self) -> list[tuple[slice, slice, slice]]:
        """Every chunk of the grid as index slices, in C order."""
        ranges = [
            [slice(i, min(i + c, n)) for i in range(0, n, c)]
            for n, c in zip(self.shape, self.chunks, strict=True)
        ]
        return list(product(*ranges))

    def arguments(self) -> dict:
        """Everything that determines the stored numbers, as plain JSON values."""
        from twoball.version import __version__

        arguments = {
            "axes": {axis.name: asdict(axis) for axis in self.axes},
            "height": self.height,
            "eps12": self.eps12,
            "chunks": list(self.chunks),
            "dtype": self.dtype,
            "solver": SOLVER,
            "twoball_version": __version__,
        }
        if self.force != "linear":  # only then: linear stores made before keep resuming
            arguments.update(force=self.force, solver=_hertz().SOLVER)
        return arguments

    def command(self, store: str | os.PathLike) -> str:
        """The ``twoball sweep`` command that computes this grid into ``store``."""
        words = ["twoball", "sweep", str(store)]
        for axis in self.axes:
            words += [f"--{axis.name.replace('_', '-')}", axis.text()]
        words += ["--height", repr(self.height)]
        if self.eps12 is not None:
            words += ["--eps12", repr(self.eps12)]
        words += ["--chunks", ",".join(str(c) for c in self.chunks), "--dtype", self.dtype]
        if self.force != "linear":
            words += ["--force", self.force]
        return " ".join(words)


def compute_block(
    eps: np.ndarray,
    mu: np.ndarray,
    tau_ratio: np.ndarray,
    *,
    height: float = DEFAULT_HEIGHT,
    eps12: float | None = None,
) -> dict[str, np.ndarray]:
    """Every cube variable (float64, bool for delayed_rebound, int8 for status) on the outer
    grid of the three 1-d arrays, with the per-drop setup of docs/model.md ("Restitution and
    damping",
    "Initial condition") done exactly as :func:`twoball.check_parameters` does it."""
    eps, mu, tau_ratio = (np.asarray(a, dtype=float) for a in (eps, mu, tau_ratio))
    # The model's own scalar functions, not vectorised twins: one definition of each quantity,
    # and over a chunk's few eps and mu values they cost < 1 % of the chunk's drops.
    zeta01 = np.array([decay_ratio(e) for e in eps])
    zeta12 = np.array([[damping_ratios(e, e if eps12 is None else eps12, m)[1] for m in mu]
                       for e in eps])  # fmt: skip
    tau_f = [floor_contact_time(z) for z in zeta01]
    x2_0_plane = np.array([[initial_gap_height(height, t * f) for t in tau_ratio] for f in tau_f])
    shape = (eps.size, mu.size, tau_ratio.size)
    apex_h = np.full((2, *shape), np.nan)
    apex_t = np.full((2, *shape), np.nan)
    contacts = np.full(shape, np.nan)
    status = np.zeros(shape, dtype=np.int8)
    runs.run_block(mu, zeta01, zeta12, x2_0_plane, height, apex_h, apex_t, contacts, status)
    x2_0 = np.broadcast_to(x2_0_plane[:, None, :], shape)
    eps01 = eps[:, None, None]
    h_icm = icm_height(
        height, x2_0 - height, eps01, eps01 if eps12 is None else eps12, mu[None, :, None]
    )
    h1, h2 = apex_h
    return {
        "h1": h1,
        "h2": h2,
        "t1": apex_t[0],
        "t2": apex_t[1],
        "contacts_first": contacts,
        "h_icm": h_icm,
        "x2_0": np.array(x2_0),
        **ratios(h1, h2, x2_0, h_icm),
        "delayed_rebound": h2 > h1,  # False where h2 is NaN
        "status": status,
    }


def compute_chunk(grid: Grid, index: tuple[slice, slice, slice]) -> dict[str, np.ndarray]:
    """One chunk of ``grid`` (runs on a worker)."""
    values = [axis.values()[part] for axis, part in zip(grid.axes, index, strict=True)]
    if grid.force == "hertz":
        return _hertz().compute_block(*values, height=grid.height, eps12=grid.eps12)
    return compute_block(*values, height=grid.height, eps12=grid.eps12)


def _stored_type(grid: Grid, name: str) -> str:
    return {"delayed_rebound": "bool", "status": "int8"}.get(name, grid.dtype)


def _template(grid: Grid, command: str):
    """The empty cube (lazy, nothing computed): coordinates, variables' metadata, attributes."""
    import dask.array as da
    import xarray as xr

    from twoball.version import __version__

    data_vars = {}
    for name, (units, long_name) in VARIABLES.items():
        dtype = _stored_type(grid, name)
        fill = np.nan if dtype.startswith("float") else 0
        attrs = {"units": units, "long_name": long_name}
        if name == "contacts_first":
            attrs["description"] = CONTACTS_DESCRIPTION
        if name == "status":
            attrs["flag_values"] = list(STATUS_FLAGS)
            attrs["flag_meanings"] = " ".join(STATUS_FLAGS.values())
        data = da.full(grid.shape, fill, dtype=dtype, chunks=grid.chunks)
        data_vars[name] = (DIMS, data, attrs)
    coords = {
        axis.name: (
            axis.name,
            axis.values(),
            {"units": "1", "long_name": COORDINATES[axis.name], "spacing": axis.spacing},
        )
        for axis in grid.axes
    }
    attrs = {
        "title": "two-ball bounce sweep (twoball, exact solver)",
        "height": grid.height,
        "eps12": "equal to eps" if grid.eps12 is None else grid.eps12,
        "grid": json.dumps({a.name: asdict(a) for a in grid.axes}),
        "solver": SOLVER + " (closed-form phase-by-phase solver, docs/model.md)",
        "twoball_version": __version__,
        "precision": f"{grid.dtype} floats, computed in float64",
        "sweep_command": command,
        "sweep_arguments": json.dumps(grid.arguments(), sort_keys=True),
        "conventions": "a chunk is finished when _progress/<chunk index> exists",
    }
    dataset = xr.Dataset(data_vars, coords=coords, attrs=attrs)
    if grid.force == "hertz":
        _hertz().annotate(dataset, grid.height)
    return dataset


def _open_or_create(grid: Grid, store: Path) -> set[str]:
    """Create the empty store (atomically), or check an existing one was written with the same
    arguments; return the keys of the chunks already finished."""
    import zarr
    from zarr.codecs import BloscCodec

    wanted = grid.arguments()
    if store.exists():
        try:
            attrs = json.loads((store / "zarr.json").read_text())["attributes"]
            found = json.loads(attrs["sweep_arguments"])
        except (OSError, KeyError, ValueError):
            raise ParameterError(
                f"{store} exists and is not a twoball sweep store: refusing to overwrite it"
            ) from None
        if found != wanted:
            differences = sorted(k for k in wanted if wanted[k] != found.get(k))
            raise ParameterError(
                f"{store} was written by a sweep with other arguments (differing: "
                f"{', '.join(differences)}; it was made by: {attrs.get('sweep_command')}); "
                "refusing to overwrite it: choose another store or delete it"
            )
    else:
        store.parent.mkdir(parents=True, exist_ok=True)
        building = store.with_name(store.name + ".creating")
        shutil.rmtree(building, ignore_errors=True)  # left by a run killed while creating
        template = _template(grid, grid.command(store))
        # byte shuffle + zstd: 15 % smaller than plain zstd on these smooth float fields; level
        # 7 stores the paper's cube 0.2 % larger than level 9 for a quarter of its CPU (0.11
        # against 0.43 s, a third of the time the kernel takes to compute the cube)
        compressor = BloscCodec(cname="zstd", clevel=7, shuffle="shuffle")
        # chunk files named c.I.J.K in the variable's directory: nested c/I/J/K directories
        # cost two directory creations per chunk and variable, more than writing the chunk
        flat = {"name": "default", "separator": "."}
        encoding = {
            name: {"chunks": grid.chunks, "compressors": [compressor], "chunk_key_encoding": flat}
            for name in VARIABLES
        }
        template.to_zarr(building, compute=False, encoding=encoding, consolidated=False)
        zarr.open_group(building / PROGRESS_DIR, mode="w")  # a group, so readers skip it
        os.replace(building, store)
    return {path.name for path in (store / PROGRESS_DIR).iterdir() if path.name != "zarr.json"}


def _chunk_key(grid: Grid, index: tuple[slice, slice, slice]) -> str:
    return ".".join(str(part.start // c) for part, c in zip(index, grid.chunks, strict=True))


def _open_variables(store: Path) -> dict:
    """The cube's data variables as Zarr arrays, opened once for all the chunks' writes."""
    import zarr

    group = zarr.open_group(str(store), mode="r+")
    return {name: group[name] for name in VARIABLES}


def _write_chunk(grid: Grid, store: Path, variables: dict, index, arrays: dict) -> None:
    """Write one finished chunk, then its done-marker (a marker is never ahead of the data).

    Straight into the Zarr arrays (the stored types are plain: no encoding to apply); through
    xarray's region writes each chunk cost ~0.1 s of opening and checking the store, twice the
    time the compiled kernel takes to compute it.
    """
    for name, target in variables.items():
        target[index] = arrays[name].astype(_stored_type(grid, name), copy=False)
    (store / PROGRESS_DIR / _chunk_key(grid, index)).touch()


def _compute_and_write(grid: Grid, store: Path, variables: dict, index) -> None:
    _write_chunk(grid, store, variables, index, compute_chunk(grid, index))


def sweep(
    grid: Grid,
    store: str | os.PathLike,
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    progress: bool = True,
):
    """Compute ``grid`` into a Zarr store, resuming from any chunks already finished there.

    Every finished chunk is written at once, so a sweep stopped even by kill -9 resumes when
    started again with the same arguments. A lock file beside the store keeps a second sweep
    off it; the store's metadata is consolidated when it is complete.

    Parameters
    ----------
    grid : Grid
        What to compute.
    store : str or path
        The Zarr directory to write (created if absent).
    scheduler : str, optional
        Address of a Dask distributed scheduler (e.g. tcp://127.0.0.1:8786): its workers
        compute, this process writes, so they need no shared disk.
    workers : int, optional
        Local threads when no scheduler is given (default: all cores; the batch path releases
        the GIL).
    progress : bool
        Show a progress bar with the time left on stderr.

    Returns
    -------
    xarray.Dataset
        The finished cube, opened lazily (as :func:`twoball.load_cube` opens it).

    Raises
    ------
    ParameterError
        A store written with other arguments or being written by another sweep, bad workers,
        an unreachable scheduler.

    Examples
    --------
    >>> from twoball.batch.sweep import Grid, parse_axis, sweep
    >>> grid = Grid(parse_axis("eps", "0.816"), parse_axis("mu", "0.05"),
    ...             parse_axis("tau_ratio", "0.3"))
    >>> import pathlib, tempfile
    >>> store = pathlib.Path(tempfile.mkdtemp()) / "cube.zarr"
    >>> cube = sweep(grid, store, workers=1, progress=False)
    >>> round(float(cube.h1.squeeze()), 3)  # docs/model.md's check value 26344.4166
    26344.417
    """
    from tqdm import tqdm

    store = Path(store)
    if workers is not None and (not isinstance(workers, int) or workers < 1):
        raise ParameterError(f"workers must be an integer >= 1; got {workers!r}")
    if scheduler is not None and workers is not None:
        raise ParameterError("workers applies to local runs only, not with a scheduler")
    client = None if scheduler is None else _connect(scheduler)
    lock = _lock(store)
    try:
        done = _open_or_create(grid, store)
        variables = _open_variables(store)
        todo = [index for index in grid.chunk_slices() if _chunk_key(grid, index) not in done]
        bar = tqdm(
            total=grid.size,
            initial=grid.size - sum(_cases(index) for index in todo),
            unit="case",
            unit_scale=True,
            desc=f"sweep {store.name}",
            file=sys.stderr,
            disable=not progress,
            smoothing=0.1,
        )
        with bar:
            if client is not None:
                from distributed import as_completed

                futures = {
                    client.submit(compute_chunk, grid, index, pure=False): index for index in todo
                }
                for future in as_completed(list(futures)):
                    _write_chunk(grid, store, variables, futures[future], future.result())
                    bar.update(_cases(futures[future]))
            elif todo:
                # Threads, not processes: the batch path (runs.run_block) runs compiled with
                # the GIL released, so threads compute in parallel with no start-up cost. Each
                # thread writes its own chunks, so writing one chunk overlaps computing others.
                threads = min(workers or os.cpu_count() or 1, len(todo))
                with ThreadPoolExecutor(threads) as pool:
                    futures = {
                        pool.submit(_compute_and_write, grid, store, variables, index): index
                        for index in todo
                    }
                    for future in threads_completed(futures):
                        future.result()
                        bar.update(_cases(futures[future]))
        # complete: one metadata document, so that xarray.open_zarr reads it without a
        # warning (written under the lock: no other sweep changes the store meanwhile)
        import warnings

        import zarr

        with warnings.catch_warnings():
            # zarr notes that consolidation is not in the v3 spec (xarray relies on it), and
            # that the done-markers in _progress/ are not zarr objects: both known and harmless
            warnings.simplefilter("ignore", UserWarning)
            zarr.consolidate_metadata(str(store))
    finally:
        lock.unlink(missing_ok=True)
        if client is not None:
            client.close()
    from twoball.batch.cubes import load_cube

    return load_cube(store)


def _lock(store: Path) -> Path:
    """Take ``STORE.lock`` (holding this process's id), or ValueError naming the sweep that
    holds it; a lock left by a process that is gone is taken over."""
    lock = store.with_name(store.name + ".lock")
    store.parent.mkdir(parents=True, exist_ok=True)
    for _ in range(2):
        try:
            descriptor = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            try:
                holder = int(lock.read_text() or "0")
                os.kill(holder, 0)
            except (ValueError, ProcessLookupError, FileNotFoundError):
                lock.unlink(missing_ok=True)  # its sweep was killed: resume from its chunks
                continue
            except PermissionError:
                pass  # alive, another user's
            raise ParameterError(
                f"{store} is being written by another sweep (process {holder}); nothing was "
                f"changed: wait for it to finish, then run again to resume or check the cube"
            ) from None
        with os.fdopen(descriptor, "w") as handle:
            handle.write(str(os.getpid()))
        return lock
    raise ParameterError(f"could not take the lock {lock}")


def plan(grid: Grid, workers: int) -> str:
    """What a sweep undertakes, in words: drops, estimated time on ``workers``, stored size.

    Parameters
    ----------
    grid : Grid
        The sweep.
    workers : int
        Processes it will run on.

    Returns
    -------
    str

    Examples
    --------
    >>> from twoball.batch.sweep import Grid, parse_axis, plan
    >>> grid = Grid(parse_axis("eps", "0.5:1:50"), parse_axis("mu", "0.01:1/3:50"),
    ...             parse_axis("tau_ratio", "0.01:1:50"))
    >>> plan(grid, 2).split(", about")[0]
    '125,000 drops (50 x 50 x 50)'
    """
    rate = DROPS_PER_WORKER_SECOND if grid.force == "linear" else _hertz().DROPS_PER_WORKER_SECOND
    seconds = grid.size / (rate * workers)
    stored = 4 if grid.dtype == "float32" else 8
    megabytes = grid.size * len(VARIABLES) * stored / 1e6
    shape = " x ".join(str(n) for n in grid.shape)
    stored_text = f"{megabytes:,.0f} MB" if megabytes >= 1 else "1 MB"
    return (
        f"{grid.size:,} drop{'s' if grid.size > 1 else ''} ({shape}), about "
        f"{_duration(seconds)} on {workers} worker{'s' if workers > 1 else ''} (once the solver "
        f"is compiled), at most {stored_text} stored (before compression)"
    )


def max_drops(grid: Grid) -> int:
    """The drops a sweep of ``grid`` undertakes without being told to (about an hour's work)."""
    return MAX_DROPS if grid.force == "linear" else MAX_HERTZ_DROPS


def _hertz():
    """:mod:`twoball.batch.hertz_sweep`, imported when a Hertz grid needs it."""
    from twoball.batch import hertz_sweep

    return hertz_sweep


def _duration(seconds: float) -> str:
    for unit, size in (("days", 86400), ("h", 3600), ("min", 60)):
        if seconds >= size:
            return f"{seconds / size:,.1f} {unit}"
    return f"{seconds:.0f} s" if seconds >= 1 else "1 s"


def _connect(scheduler: str):
    """A client of the Dask scheduler at ``scheduler``, or ValueError saying it is unreachable."""
    from distributed import Client

    try:
        return Client(scheduler, timeout=SCHEDULER_TIMEOUT)
    except (OSError, TimeoutError, ValueError, TypeError) as error:
        raise ParameterError(
            f"scheduler: cannot reach a Dask scheduler at {scheduler!r} within "
            f"{SCHEDULER_TIMEOUT} ({type(error).__name__}: {error})"
        ) from None


def _cases(index: tuple[slice, slice, slice]) -> int:
    return math.prod(part.stop - part.start for part in index)
