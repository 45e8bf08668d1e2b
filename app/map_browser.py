"""What the delayed-rebound map computes in the browser (app/delayed_map.py draws the map): a
slice's values decoded from the codes the server sends, the Hertz cubes' cells placed from
their index, and the hover's and the axes' text.

Issue 21, "send what the screen needs": the map's first document was 57 kB (the linear map)
and 102 kB (the Hertz map) where the other pages' are 35-42 kB. Decided:

- A slice's values travel as uint16 codes (app/map_slices.py ``encoded``), not float32: 12 kB
  for the linear map's 81 x 73 pixels, not 24; 5 kB for the Hertz map's 2500 cells, not 10.
  A code is a value to three significant digits, exactly the number the hover shows: Python's
  ``f"{value:.3g}"``, JavaScript's ``Number(value.toPrecision(3))``. Code 0 is 0; codes from 1
  are positive values, decade by decade (900 a decade: the mantissas 100..999), from 1.00e-18
  to 9.99e17; from 32768 the negative values likewise; :data:`NO_CODE` (65535) is no value,
  decoded to NaN (grey or transparent, as before). A magnitude beyond those decades (none of
  the shipped cubes': their values run from 1.4e-5 to 80) is clipped to the nearest end.
  Decoding is a formula (:data:`DECODE_JS`), the value read from its digits, ``"197e-2"``, as
  Python's ``float("1.97")`` reads it: the same double, no table sent.
- An earlier coding (steps of 7e-5 decades, each colour band a whole number of codes) kept
  each cell's colour but gave its value to 1e-4 only: the hover's third decimal was wrong for a
  few % of the cells (h2/h1) and up to 1 in 6 (h2/H), and a student reading the map and then
  the Drop (h2/h1 to 4 decimals) saw two numbers. The hover now prints the code's three digits
  (:data:`VALUE_JS`, the text ``.3g`` gives: "1.97", "0.0123", "23.8", "1.48e-05"), and the
  cell is coloured from that rounded value: a value rounded across the boundary of two of the
  256 shades takes the next shade (never more; a count, a whole number below 1000, is exact).
- The Hertz map's cells are placed in the browser from their index and the two axes' cell
  edges (:func:`cell_edge`): their edges, mu and tau_ratio per cell were 60 kB of the 102.
  The hover finds the cell under the pointer as on the image (:data:`CELL_JS`: the cells'
  edges lie half-way between the axis values in log10).
- The hover decodes the code under the pointer (:data:`VALUE_JS`), so "none" now shows where
  a ratio has none: Bokeh printed "NaN" for a NaN before the custom formatter ran.
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from bokeh.core.property.vectorization import Expr
from bokeh.models import ColorMapper, CustomJSExpr, CustomJSHover, HoverTool

from .map_slices import (
    FIRST_DECADE,
    MANTISSAS,
    NEGATIVE_CODES,
    NO_CODE,
    POSITIVE_CODES,
    ZERO_CODE,
    cell_edges,
)
from .scene import on_screen

# a code's sign, decade and mantissa (app/map_slices.py ``encoded``)
DIGITS_JS = f"""
const NO_CODE = {NO_CODE}, ZERO_CODE = {ZERO_CODE};
const digits = (code) => {{
  const negative = code >= {NEGATIVE_CODES};
  const k = code - (negative ? {NEGATIVE_CODES} : {POSITIVE_CODES});
  const decade = {FIRST_DECADE} + Math.floor(k / {MANTISSAS});
  return [negative ? "-" : "", decade, 100 + (k % {MANTISSAS})];
}};
"""
# a code's value: the double nearest mantissa * 10 ** (decade - 2), read from its digits as
# Python's float() reads them
DECODE_JS = (
    DIGITS_JS
    + """
const decode = (code) => {
  if (code == NO_CODE) return NaN;
  if (code == ZERO_CODE) return 0;
  const [sign, decade, mantissa] = digits(code);
  return Number(`${sign}${mantissa}e${decade - 2}`);
};
"""
)
# the image's values from its codes, an array of the same shape (``this``: the image's source)
IMAGE_JS = (
    DECODE_JS
    + """
const {ndarray} = Bokeh.require("core/util/ndarray");
return this.get_column("image").map((codes) => {
  const values = new Float64Array(codes.length);
  for (let i = 0; i < codes.length; i++) values[i] = decode(codes[i]);
  return ndarray(values, {dtype: "float64", shape: codes.shape});
});
"""
)
# the cells' values from their codes (``this``: the cells' source)
CELLS_JS = DECODE_JS + 'return Float64Array.from(this.get_column("value"), decode);'
# one edge of every cell (k: rows tau_ratio, columns mu), from the edges along its axis
EDGE_JS = """
const count = this.get_length(), edges_of = new Float64Array(count);
for (let k = 0; k < count; k++)
  edges_of[k] = edges[(across ? Math.floor(k / columns) : k % columns) + upper];
return edges_of;
"""
# the hover's value: its code's three significant digits, as Python's f"{value:.3g}" writes
# them (fixed from 1e-4 to 999, else "1.48e-05"), and a cell without a value said so
VALUE_JS = (
    DIGITS_JS
    + """
if (value == NO_CODE) return "none: an apex below 0, or missing";
if (value == ZERO_CODE) return "0";
const [sign, decade, mantissa] = digits(value);
const text = String(mantissa), trimmed = (tail) => tail.replace(/0+$/, "");
if (decade < -4 || decade > 2) {
  const tail = trimmed(text.slice(1)), power = String(Math.abs(decade)).padStart(2, "0");
  return `${sign}${text[0]}${tail ? "." + tail : ""}e${decade < 0 ? "-" : "+"}${power}`;
}
const whole = decade < 0 ? "0" : text.slice(0, decade + 1);
const tail = trimmed(decade < 0 ? "0".repeat(-decade - 1) + text : text.slice(decade + 1));
return `${sign}${whole}${tail ? "." + tail : ""}`;
"""
)
# the computed cell nearest the pointer on an axis (log10 values ``logs``), as a number
CELL_JS = """
let best = logs[0];
for (const log of logs) if (Math.abs(log - value) < Math.abs(best - value)) best = log;
return (10 ** best).toPrecision(3);
"""
# a log axis's tick label: the value itself; over more than two decades in view, the powers of
# ten alone (1, 2 and 5 each labelled, a narrow projected or phone map dropped "0.01" and "0.1"
# for lack of room), the others marked by their ticks
LOG_TICK_JS = """
const decade = Math.abs(tick - Math.round(tick)) < 1e-9;
if (ticks[ticks.length - 1] - ticks[0] > 2 && !decade) return "";
return String(Number((10 ** tick).toPrecision(3)));
"""


def decoded_image() -> Expr:
    """The image's values, decoded in the browser from the codes in its source (column
    ``image``)."""
    return Expr(CustomJSExpr(code=IMAGE_JS))


def decoded_cells(mapper: ColorMapper) -> Expr:
    """The cells' colours: their values decoded in the browser from their codes (column
    ``value``), coloured by ``mapper``."""
    return Expr(CustomJSExpr(code=CELLS_JS), transform=mapper)


def cell_edge(cube: xr.Dataset, axis: str, upper: bool) -> Expr:
    """One edge of every cell of ``cube`` (left, right: ``axis`` mu; bottom, top: tau_ratio),
    placed in the browser from the cell's index (rows tau_ratio, columns mu) and the edges
    along that axis (app/map_slices.py ``cell_edges``)."""
    args = {
        "edges": on_screen(cell_edges(cube[axis].values)),
        "columns": cube.sizes["mu"],
        "across": axis == "tau_ratio",
        "upper": int(upper),
    }
    return Expr(CustomJSExpr(args=args, code=EDGE_JS))


def values_hover(label: str, cube: xr.Dataset, cells: bool) -> HoverTool:
    """The map's hover: the mu and tau_d/tau_f of the computed cell under the pointer (what a
    click chooses, app/delayed_map.py ``MapScene._tapped``) as numbers, not the log10 the map
    is drawn in, and its value read from its code (a new model each time: a Bokeh model
    belongs to one session's document). The pointer's own coordinates had given a value that
    was not that point's: the map read 1.973 where the Drop, at the clicked point, gave 2.014.

    The cell is looked for in the browser (:data:`CELL_JS`), on the image as on the cells
    (``cells``: the Hertz cubes')."""
    axes = {
        f"${at}": CustomJSHover(args={"logs": on_screen(np.log10(cube[axis].values))}, code=CELL_JS)
        for at, axis in (("x", "mu"), ("y", "tau_ratio"))
    }
    field = "@value" if cells else "@image"
    return HoverTool(
        tooltips=[
            ("mu", "$x{custom}"),
            ("tau_d/tau_f", "$y{custom}"),
            (label, f"{field}{{custom}}"),
        ],
        formatters={**axes, field: CustomJSHover(code=VALUE_JS)},
        # (over a rectangle the tooltip follows the pointer, as over the image)
        **({"point_policy": "follow_mouse"} if cells else {}),
    )
