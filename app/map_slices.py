"""The delayed-rebound map's data: the shipped cubes (the linear "map" cube and the two-ball
Hertz cubes), their eps slices on the map's log grid, slices computed for another drop, the
outline of the delayed rebounds, and colour limits. No drawing here (app/delayed_map.py draws).

Only the slice on screen is read from a cube (one chunk per variable), and slices are kept for
all sessions. For a drop whose H or eps12 differ from the cube's, or whose eps lies outside it,
the slice is computed on the cube's axes with the sweep's batch path (:func:`computed_slice`,
~6000 drops in a fraction of a second) once the solver is compiled.

The Hertz cubes (``hertz-h1e2``, ``hertz-h1e4``: the paper's linear grid, 50 values per axis)
have their H in the Hertz length unit, and their tau_ratio counts the Hertz floor contact
(twoball/precomputed/README.md). Their axes are evenly spaced in mu and tau_ratio, not in
log10: the map draws them as one rectangle per cell (:func:`drawn_as_cells`, :func:`cell_edges`,
:func:`slice_cells`), an eps move sending the cells' values alone; the map cube's slices are
one image (:func:`slice_image`). Either's values travel as uint16 codes, each a value to three
significant digits (:func:`encoded`), decoded in the browser (app/map_browser.py says why).
"""

from __future__ import annotations

import functools
import math
import re

import numpy as np
import panel as pn
import xarray as xr
from contourpy import LineType, contour_generator
from scipy import ndimage

import twoball
from twoball.batch.sweep import compute_block

from .state import MAP_COLOURS

CUBE = "map"
# the shipped two-ball Hertz cubes by their drop height H (in the Hertz length unit)
HERTZ_CUBES = {1e2: "hertz-h1e2", 1e4: "hertz-h1e4"}
MOST_PIXELS = 400  # per axis, of a cube not evenly spaced in log10 (log_grid)
SMALLEST_OUTLINED = 4  # cells: a delayed-rebound patch smaller than this is not outlined

RATIO_CENTRES = {"h2_over_h1": 1.0, "h1_over_icm": 1.0}
# whole numbers: coloured one colour each (:func:`count_palette`), not a gradient whose shades
# between two counts stand for nothing
COUNTS = ("contacts_first",)
# a variable's words for a class, in the choice and on the colour bar alike (the cube's own
# names, "h1 / h_ICM", "h1 / X2(0)", are the library's: a new user could not read them, and the
# choice and the bar named the count differently)
LABELS = {
    "h2_over_h1": "h2 / h1",
    "h1_over_icm": "h1 / textbook (ICM) height",
    "h1_over_drop": "h1 / drop height",
    "h2_over_drop": "h2 / drop height",
    "contacts_first": "ball contacts before h1",
}


def variable_label(variable: str) -> str:
    """The cube's own name of a variable (its ``long_name``), without the library's name for it
    in parentheses (a colour bar titled "... (Result.contacts_first[1])" was code to a class)."""
    name = map_cube()[variable].attrs.get("long_name", variable)
    return re.sub(r"\s*\(Result\.[^)]*\)", "", name)


def shown_label(variable: str) -> str:
    """A variable's name on the map (:data:`LABELS`), the cube's own for one not listed."""
    return LABELS.get(variable, variable_label(variable))


@functools.cache
def shown_cube(name: str) -> xr.Dataset:
    """A shipped cube the map shows ("map" or a Hertz one), opened lazily once per server."""
    return twoball.load_cube(name)


def map_cube() -> xr.Dataset:
    """The shipped (linear) map cube, opened lazily once per server."""
    return shown_cube(CUBE)


def hertz_cube_name(height: float) -> str:
    """The shipped Hertz cube whose drop height is nearest ``height`` (on a log scale)."""
    nearest = min(HERTZ_CUBES, key=lambda h: abs(math.log10(h) - math.log10(height)))
    return HERTZ_CUBES[nearest]


@pn.cache(max_items=128)  # shared by every session of the server, as the cube is
def eps_slice(eps: float, variable: str, name: str = CUBE) -> xr.Dataset:
    """One variable and the delayed-rebound flags at one of the cube's eps values."""
    return shown_cube(name)[[variable, "delayed_rebound"]].sel(eps=eps).load()


def evenly_logged(values: np.ndarray) -> bool:
    """Whether an axis (mu or tau_ratio) is evenly spaced in log10 (the map cube's)."""
    steps = np.diff(np.log10(np.asarray(values, dtype=float)))
    return steps.size == 0 or bool(np.allclose(steps, steps[0], rtol=1e-6, atol=0.0))


def drawn_as_cells(cube: xr.Dataset) -> bool:
    """Whether the map draws a cube's slices as one rectangle per cell (:func:`cell_edges`),
    not one image: an axis not evenly spaced in log10 (the Hertz cubes'). On an image such an
    axis needed a pixel for its narrowest cell (:func:`log_grid`): 177 x 227 float32 pixels for
    2500 cells, 160 kB sent to every browser on every eps move, where the cells' values alone
    are 10 kB."""
    return not (evenly_logged(cube["mu"].values) and evenly_logged(cube["tau_ratio"].values))


def cell_edges(values: np.ndarray) -> np.ndarray:
    """The log10 edges of an axis's cells (``values.size + 1``): half-way between neighbouring
    values in log10, the outer edges the outer values (the cube's range, no more, as the
    image was drawn: a half cell beyond would widen the Hertz map's axes by a quarter of a
    decade). Every point of a cell is nearer its own value in log10 than any other: a click or
    a hover in a cell is that cell's (:func:`nearest_on_log_axis`)."""
    logs = np.log10(np.asarray(values, dtype=float))
    return np.concatenate([logs[:1], (logs[1:] + logs[:-1]) / 2, logs[-1:]])


def log_grid(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Evenly spaced log10 pixel centres over an axis, and the index of the axis value each
    pixel shows (the nearest in log10).

    An axis evenly spaced in log10 (the map cube's) is its own grid. Another (the Hertz cubes',
    evenly spaced in the value) gets enough pixels for its narrowest cell to have one, at most
    :data:`MOST_PIXELS`: each pixel shows a computed cell, none is interpolated."""
    logs = np.log10(np.asarray(values, dtype=float))
    if evenly_logged(values):
        return logs, np.arange(logs.size)
    steps = np.diff(logs)
    count = min(MOST_PIXELS, int(math.ceil((logs[-1] - logs[0]) / steps.min())) + 1)
    grid = np.linspace(logs[0], logs[-1], count)
    return grid, np.searchsorted((logs[1:] + logs[:-1]) / 2, grid)


def on_log_grid(slice_: xr.Dataset, values: np.ndarray) -> tuple:
    """(log10 mu, log10 tau_ratio, values as (tau_ratio, mu)) to draw as one image."""
    log_mu, mu_index = log_grid(slice_["mu"].values)
    log_tau, tau_index = log_grid(slice_["tau_ratio"].values)
    return log_mu, log_tau, np.asarray(values)[np.ix_(tau_index, mu_index)]


@pn.cache(max_items=32)
def computed_slice(eps: float, height: float, eps12: float | None) -> xr.Dataset:
    """The map's slice at ``eps`` for another drop height or ball-ball restitution than the
    cube's, computed on the cube's mu and tau_ratio axes with the sweep's batch path (about
    6000 drops, a fraction of a second compiled); kept for all sessions."""
    cube = map_cube()
    mu, tau_ratio = cube["mu"].values, cube["tau_ratio"].values
    block = compute_block([eps], mu, tau_ratio, height=height, eps12=eps12)
    variables = {
        name: (("mu", "tau_ratio"), block[name][0], cube[name].attrs)
        for name in (*MAP_COLOURS, "delayed_rebound")
    }
    return xr.Dataset(variables, coords={"mu": mu, "tau_ratio": tau_ratio, "eps": eps})


def nearest_on_log_axis(values: np.ndarray, log_value: float) -> int:
    """The index of the axis value (mu or tau_ratio) nearest ``log_value`` on the map's log10
    axis: the computed cell a pixel, a click or the star is in."""
    return int(np.abs(np.log10(values) - log_value).argmin())


def nearest_eps(eps: float, name: str = CUBE) -> float:
    """The eps of the cube ``name`` nearest to ``eps``."""
    values = shown_cube(name)["eps"].values
    return float(values[np.abs(values - eps).argmin()])


def outlined(delayed: np.ndarray, smallest: int = SMALLEST_OUTLINED) -> np.ndarray:
    """The delayed-rebound flags as outlined: a patch (or a hole) of fewer than ``smallest``
    cells takes its surroundings' value. Its colour still shows it; outlined, single cells drew
    small diamonds that read as noise from the back of a room."""
    kept = np.asarray(delayed, dtype=bool).copy()
    for value in (True, False):
        patches, count = ndimage.label(kept == value)
        sizes = np.bincount(patches.ravel())
        small = np.flatnonzero(sizes < smallest)
        kept[np.isin(patches, small[small > 0])] = not value
    return kept


def colour_limits(values: np.ndarray, variable: str) -> tuple[float, float]:
    """The colour limits of ``values``: for a ratio, symmetric about 1 on a log scale out to
    the 98th percentile (so that outliers do not wash it out); for a count, half a count beyond
    its smallest and largest (a band of :func:`count_palette` each); for the others the values'
    own range."""
    values = np.asarray(values)
    if variable in RATIO_CENTRES:
        finite = values[np.isfinite(values) & (values > 0)]
        spread = float(np.percentile(np.abs(np.log10(finite)), 98)) if finite.size else 1.0
        spread = max(spread, 0.05)
        return 10**-spread, 10**spread
    finite = values[np.isfinite(values)]
    low, high = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    if variable in COUNTS:
        return round(low) - 0.5, round(high) + 0.5  # (count_palette)
    return low, high


@functools.cache  # (a variable of a cube read once per server: about 120 000 values)
def cube_colour_limits(name: str, variable: str) -> tuple[float, float]:
    """The colour limits of a shipped cube's ``variable`` over all its eps: every slice of it
    in the same colours, so that a colour means one value whatever eps is shown (each slice's
    own had made the h2/h1 scale run 0.15-6.6 at eps 0.9 and 0.05-20 at 0.5)."""
    return colour_limits(shown_cube(name)[variable].values, variable)


# A value's uint16 code (:func:`encoded`): its three significant digits, a mantissa 100..999
# and a decade (10**decade <= |value| < 10**(decade + 1)), decoded in the browser
# (app/map_browser.py says why)
MANTISSAS = 900  # the codes of a decade (mantissas 100..999)
FIRST_DECADE, LAST_DECADE = -18, 17  # (36 decades: 32400 codes a sign)
POSITIVE_CODES, NEGATIVE_CODES = 1, 32768  # the code of +-100e(FIRST_DECADE - 2)
ZERO_CODE = 0
NO_CODE = 65535  # a cell without a value
# a scaled magnitude (100 to 1000) this near a rounding tie or its decade's ends is coded by
# Python's own formatting (:func:`encoded`): NumPy's is within 1e-10 of the exact value
DOUBTFUL = 1e-6


def encoded(values: np.ndarray) -> np.ndarray:
    """``values`` (a slice's :func:`shown_values`) as uint16 codes, each standing for the value
    rounded to three significant digits (Python's ``f"{value:.3g}"``): NaN or infinite (no
    value) :data:`NO_CODE`, 0 :data:`ZERO_CODE`, else the sign's first code plus
    ``(decade - FIRST_DECADE) * MANTISSAS + mantissa - 100``. A magnitude beyond the decades
    (above 9.99e17 or below 1e-18: none of the shipped cubes', 1.4e-5 to 80) is clipped to the
    largest or smallest.

    Worked out in NumPy; a value whose scaled magnitude lies within :data:`DOUBTFUL` of a
    rounding tie or of its decade's ends, where binary arithmetic might round otherwise than
    Python's decimal formatting, takes Python's own digits (:func:`decimal_digits`): one value
    at a time, a slice took 7 ms at every eps move."""
    values = np.asarray(values, dtype=float)
    magnitude = np.abs(values)
    valued = np.isfinite(values) & (magnitude > 0)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        decade = np.floor(np.log10(magnitude))
        scaled = magnitude / 10.0 ** (decade - 2)  # (in [100, 1000) but for rounding)
    mantissa = np.rint(scaled)
    doubtful = valued & (
        (np.abs(scaled - np.floor(scaled) - 0.5) < DOUBTFUL)
        | (scaled < 100 + DOUBTFUL)
        | (scaled > 999.5 - DOUBTFUL)
    )
    for index in np.flatnonzero(doubtful):
        mantissa.flat[index], decade.flat[index] = decimal_digits(float(magnitude.flat[index]))
    clipped_high, clipped_low = decade > LAST_DECADE, decade < FIRST_DECADE
    mantissa = np.where(clipped_high, 999, np.where(clipped_low, 100, mantissa))
    decade = np.clip(decade, FIRST_DECADE, LAST_DECADE)
    first = np.where(values > 0, POSITIVE_CODES, NEGATIVE_CODES)
    with np.errstate(invalid="ignore"):
        codes = first + (decade - FIRST_DECADE) * MANTISSAS + mantissa - 100
    return np.where(valued, codes, np.where(magnitude == 0, ZERO_CODE, NO_CODE)).astype(np.uint16)


def decimal_digits(magnitude: float) -> tuple[int, int]:
    """A positive value's three significant digits as Python's decimal formatting rounds them
    (``.3g``): its mantissa 100..999 and its decade."""
    digits, _, decade = f"{magnitude:.2e}".partition("e")  # ("1.97", "-05")
    return int(digits.replace(".", "")), int(decade)


def slice_image(
    slice_: xr.Dataset, variable: str, limits: tuple[float, float] | None = None
) -> tuple[tuple, tuple[float, float]]:
    """The slice's ``variable`` on the map's log grid (log10 mu, log10 tau_ratio, the codes
    with rows tau_ratio and columns mu: :func:`on_log_grid`, :func:`encoded`; a ratio's without
    a value, an apex below 0, :data:`NO_CODE`), and its colour limits: ``limits`` (a shipped
    cube's, the same for all its slices: :func:`cube_colour_limits`), else the slice's own
    (:func:`colour_limits`)."""
    values = slice_[variable].transpose("tau_ratio", "mu").values
    codes = encoded(shown_values(values, variable))
    return on_log_grid(slice_, codes), limits or colour_limits(values, variable)


def shown_values(values: np.ndarray, variable: str) -> np.ndarray:
    """A slice's ``variable`` (``values``: rows tau_ratio, columns mu) as the map colours it: a
    ratio's without a value (an apex below 0: grey, NO_RATIO) NaN."""
    if variable in RATIO_CENTRES:  # (a ratio with an apex below 0 is none: NO_RATIO)
        return np.where(values > 0, values, np.nan)
    return values


def slice_cells(
    slice_: xr.Dataset, variable: str, limits: tuple[float, float] | None = None
) -> tuple[np.ndarray, tuple[float, float]]:
    """The slice's ``variable`` one code per cell, rows tau_ratio, columns mu, flattened (the
    browser places cell k at column k % mu.size, row k // mu.size: app/map_browser.py), and its
    colour limits as :func:`slice_image`'s."""
    values = slice_[variable].transpose("tau_ratio", "mu").values
    codes = encoded(shown_values(values, variable)).ravel()
    return codes, limits or colour_limits(values, variable)


# a cell whose delayed-rebound flag disagrees with the sign of log10(h2/h1) (a patch too small
# to outline, :func:`outlined`, or a ratio missing) counts as this far on the flag's side
FLAG_SIDE = 0.05


def rebound_field(flags: xr.DataArray, ratio: xr.DataArray) -> np.ndarray:
    """log10(h2/h1) over (tau_ratio, mu), > 0 exactly where :func:`outlined` keeps a delayed
    rebound: its zero level is the outline, found between cells by interpolation."""
    kept = outlined(flags.transpose("tau_ratio", "mu").values)
    with np.errstate(divide="ignore", invalid="ignore"):
        field = np.log10(ratio.transpose("tau_ratio", "mu").values.astype(float))
    agrees = np.isfinite(field) & ((field > 0) == kept)
    return np.where(agrees, field, np.where(kept, FLAG_SIDE, -FLAG_SIDE))


def outline_path(flags: xr.DataArray, ratio: xr.DataArray) -> tuple[np.ndarray, np.ndarray]:
    """The outline of delayed rebounds (``flags``: h2 > h1 over mu and tau_ratio; ``ratio``:
    h2/h1) on the map's log axes: log10 mu and log10 tau_ratio of its vertices, the paths
    separated by NaN (one line of the figure's MultiLine).

    Marching squares (contourpy, Bokeh's own dependency) on the cube's own points, each at its
    cell's centre (log10 mu, log10 tau_ratio), on log10(h2/h1) (:func:`rebound_field`): each
    vertex lies where the ratio, interpolated between two neighbouring points, crosses 1.
    Drawn on the image's pixels, the Hertz cubes' (cells evenly spaced in mu, so several
    pixels wide on a log axis) outlines followed the cells' edges, staircases of right angles;
    and the flags alone, 0 or 1, put every vertex half-way between two points."""
    field = rebound_field(flags, ratio)
    log_mu, log_tau = np.log10(flags["mu"].values), np.log10(flags["tau_ratio"].values)
    generator = contour_generator(log_mu, log_tau, field, line_type=LineType.ChunkCombinedNan)
    ((points,),) = generator.lines(0.0)  # (one chunk: None where nothing crosses 1)
    if points is None:
        return np.zeros(0), np.zeros(0)
    return points[:, 0].copy(), points[:, 1].copy()


@functools.lru_cache(maxsize=256)  # shared by every session, as the slices are
def outline_of(
    name: str, eps: float, drop: tuple[float, float | None] | None
) -> tuple[np.ndarray, np.ndarray]:
    """The outline of the slice at ``eps`` of the cube ``name``, or (``drop``: its H and eps12)
    of the slice computed for that drop (every session moving eps asks for the same few)."""
    if drop is None:
        shown = shown_cube(name)[["delayed_rebound", "h2_over_h1"]].sel(eps=eps)
    else:
        shown = computed_slice(eps, *drop)
    return outline_path(shown["delayed_rebound"], shown["h2_over_h1"])
