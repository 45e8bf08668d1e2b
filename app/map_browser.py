"""What the delayed-rebound map computes in the browser (app/delayed_map.py draws the map): a
slice's values decoded from the codes the server sends, the Hertz cubes' cells placed from
their index, and the hover's and the axes' text.

Issue 21, "send what the screen needs": the map's first document was 57 kB (the linear map)
and 102 kB (the Hertz map) where the other pages' are 35-42 kB. Decided:

- A slice's values travel as uint16 codes (app/map_slices.py ``encoded``), not float32: 12 kB
  for the linear map's 81 x 73 pixels, not 24; 5 kB for the Hertz map's 2500 cells, not 10.
  The browser decodes them (:func:`decoded_image`, :func:`decoded_cells`) and colours the
  values with the colour mapper and colour bar they had as float32: each colour band is a
  whole number of codes (``value_coding``), so each cell keeps its colour; a value beyond the
  colour limits keeps its own code (the hover reads it) and the mapper's clamping; a cell
  without a value is :data:`NO_CODE`, decoded to NaN (grey or transparent, as before). Mapping
  the codes with a LinearColorMapper directly (no decoding) could not tell a code beyond the
  colour limits (clamped to the palette's end) from the code of no value (grey).
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
from bokeh.models import ColorMapper, ColumnDataSource, CustomJSExpr, CustomJSHover, HoverTool

from .map_slices import NO_CODE, Coding, cell_edges
from .scene import on_screen

# a code's value: ``origin``, ``step`` and ``logged`` as app/map_slices.py's Coding
DECODE_JS = f"""
const decode = (code) => code == {NO_CODE} ? NaN
  : logged ? 10 ** (origin + (code + 0.5) * step) : origin + (code + 0.5) * step;
"""
# ... their values in an image's source (one row: a computed slice has a coding of its own,
# which comes with its codes), or (the cells') in the code's own arguments
IMAGE_CODING_JS = """
const origin = source.get_column("origin")[0], step = source.get_column("step")[0];
"""
# the image's values from its codes, an array of the same shape (``this``: the image's source)
IMAGE_JS = """
const source = this;
{coding}{decode}
const {{ndarray}} = Bokeh.require("core/util/ndarray");
return source.get_column("image").map((codes) => {{
  const values = new Float64Array(codes.length);
  for (let i = 0; i < codes.length; i++) values[i] = decode(codes[i]);
  return ndarray(values, {{dtype: "float64", shape: codes.shape}});
}});
"""
# the cells' values from their codes (``this``: the cells' source)
CELLS_JS = """
{decode}
return Float64Array.from(this.get_column("value"), decode);
"""
# one edge of every cell (k: rows tau_ratio, columns mu), from the edges along its axis
EDGE_JS = """
const count = this.get_length(), edges_of = new Float64Array(count);
for (let k = 0; k < count; k++)
  edges_of[k] = edges[(across ? Math.floor(k / columns) : k % columns) + upper];
return edges_of;
"""
# the hover's value: three decimals (or three digits, below 0.01), and a cell without a value
# said so (:data:`NO_CODE`)
VALUE_JS = """{coding}{decode}
const shown = decode(value);
if (Number.isNaN(shown)) return "none: an apex below 0, or missing";
return Math.abs(shown) >= 0.01 ? shown.toFixed(3) : shown.toPrecision(3);
"""
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


def coding_args(coding: Coding) -> dict:
    """A coding as the arguments of :data:`DECODE_JS` (the cells'; an image's is in its
    source)."""
    return {"origin": coding.origin, "step": coding.step, "logged": coding.logged}


def decoded_image(source: ColumnDataSource, logged: bool) -> Expr:
    """The image's values, decoded in the browser from the codes and coding in ``source``
    (columns ``image``, ``origin``, ``step``)."""
    code = IMAGE_JS.format(coding=IMAGE_CODING_JS, decode=DECODE_JS)
    return Expr(CustomJSExpr(args={"logged": logged}, code=code))


def decoded_cells(coding: Coding, mapper: ColorMapper) -> Expr:
    """The cells' colours: their values decoded in the browser from their codes (column
    ``value``), coloured by ``mapper``."""
    expr = CustomJSExpr(args=coding_args(coding), code=CELLS_JS.format(decode=DECODE_JS))
    return Expr(expr, transform=mapper)


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


def values_hover(
    label: str, cube: xr.Dataset, source: ColumnDataSource, logged: bool, cells: Coding | None
) -> HoverTool:
    """The map's hover: the mu and tau_d/tau_f of the computed cell under the pointer (what a
    click chooses, app/delayed_map.py ``MapScene._tapped``) as numbers, not the log10 the map
    is drawn in, and its value decoded from its code (a new model each time: a Bokeh model
    belongs to one session's document). The pointer's own coordinates had given a value that
    was not that point's: the map read 1.973 where the Drop, at the clicked point, gave 2.014.

    The cell is looked for in the browser (:data:`CELL_JS`), on the image as on the cells
    (the Hertz cubes', ``cells`` their coding), in the image's ``source`` with its coding
    (``logged``: a ratio's)."""
    axes = {
        f"${at}": CustomJSHover(args={"logs": on_screen(np.log10(cube[axis].values))}, code=CELL_JS)
        for at, axis in (("x", "mu"), ("y", "tau_ratio"))
    }
    if cells is not None:
        field, args, coding = "@value", coding_args(cells), ""
    else:
        field, args, coding = "@image", {"source": source, "logged": logged}, IMAGE_CODING_JS
    value = CustomJSHover(args=args, code=VALUE_JS.format(coding=coding, decode=DECODE_JS))
    return HoverTool(
        tooltips=[
            ("mu", "$x{custom}"),
            ("tau_d/tau_f", "$y{custom}"),
            (label, f"{field}{{custom}}"),
        ],
        formatters={**axes, field: value},
        # (over a rectangle the tooltip follows the pointer, as over the image)
        **({"point_policy": "follow_mouse"} if cells is not None else {}),
    )
