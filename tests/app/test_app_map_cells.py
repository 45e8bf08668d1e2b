"""The Hertz cubes' map as one rectangle per cell (app/delayed_map.py, app/map_slices.py
``drawn_as_cells``), placed in the browser from its index (app/map_browser.py; where each lies
in the page is tests/app/test_app_map_force.py's): each cell's code stands for the value the
cube holds at its mu, tau_ratio and eps, read here from the cube itself; an eps move sends the
codes alone (the image it replaced sent 160 kB a move, the float32 values 10 kB); the hover, a
click and the grey of a cell without a ratio work on the rectangles. The map cube's image
travels as codes too."""

from __future__ import annotations

import json

import numpy as np
import pytest
from bokeh.document import Document
from bokeh.events import Tap
from bokeh.models import ColorBar, CustomJSHover, GlyphRenderer, HoverTool, Image, Quad
from bokeh.protocol import Protocol
from panel.io.state import set_curdoc
from test_app_map import code_values, three_digits

import twoball
from app.explorer import Explorer

# an eps move on the Hertz map: its 2500 codes as uint16 (5 kB), the outline and the colour
# range; the image sent 163 kB (177 x 227 float32), the cells' float32 values 12 kB
MOST_BYTES_A_MOVE = 11_000
NO_CODE = 65535  # a cell without a value


def served(query: dict) -> tuple[Explorer, Document]:
    """The explorer's page in a document as ``panel serve`` makes it (benchmarks/app_cpu.py)."""
    document = Document()
    with set_curdoc(document):
        explorer = Explorer({"scene": "map", **query})
        explorer.page().server_doc(document)
    return explorer, document


def cells_of(explorer: Explorer) -> tuple[GlyphRenderer, np.ndarray, np.ndarray]:
    """The map's rectangles' renderer, their codes and the values these stand for, decoded as
    the browser decodes them (tests/app/test_app_map.py ``code_values``)."""
    figure = explorer.scenes["map"].figure.object
    (renderer,) = [r for r in figure.select({"type": GlyphRenderer}) if isinstance(r.glyph, Quad)]
    codes = np.asarray(renderer.data_source.data["value"])
    return renderer, codes, code_values(codes)


def cube_value(name: str, variable: str, eps: float, mu: float, tau_ratio: float) -> float:
    """The cube's value at one grid point, read from the cube (not the app's slices)."""
    cube = twoball.load_cube(name)
    return float(cube[variable].sel(eps=eps, mu=mu, tau_ratio=tau_ratio))


def assert_ratios_held(values: np.ndarray, want: np.ndarray) -> None:
    """Decoded ratios are the cube's (``want``) to three significant digits, exactly as the
    hover shows them (``.3g``), NaN where it has none (<= 0: grey)."""
    np.testing.assert_array_equal(values, three_digits(np.where(want > 0, want, np.nan)))


def log_edges(values: np.ndarray) -> np.ndarray:
    """A Hertz axis's cell edges, found here again: half-way between neighbouring values in
    log10, the outer ones at the outer values."""
    logs = np.log10(values)
    return np.r_[logs[0], (logs[1:] + logs[:-1]) / 2, logs[-1]]


def patch_bytes(document: Document, move) -> tuple[int, list]:
    """The bytes of the PATCH-DOC the server sends for ``move`` (its JSON and binary buffers,
    as benchmarks/app_cpu.py counts them), and its events."""
    events: list = []
    document.on_change(events.append)
    move()
    message = Protocol().create("PATCH-DOC", list(events))
    size = len(message.content_json) + sum(len(b.to_bytes()) for b in message._buffers)
    return size, events


@pytest.mark.parametrize(("height", "name"), [(1e4, "hertz-h1e4"), (100.0, "hertz-h1e2")])
def test_each_rectangle_holds_its_cube_cell_and_its_edges(height, name):
    """Cell k is the cube's (mu[k % 50], tau_ratio[k // 50]): its code stands for the cube's
    value there, and its edges, placed in the browser, come from each axis's edges (half-way
    between neighbouring values in log10) and the cell's column or row."""
    explorer, _ = served({"map_force": "hertz", "H": f"{height:g}", "eps": "0.7"})
    scene = explorer.scenes["map"]
    assert scene.slice_cube == name
    cube = twoball.load_cube(name)
    mus, taus = cube["mu"].values, cube["tau_ratio"].values
    renderer, codes, values = cells_of(explorer)
    assert codes.dtype == np.uint16 and codes.size == mus.size * taus.size == 2500
    assert set(renderer.data_source.data) == {"value"}  # (nothing per cell but its code)
    for k in np.random.default_rng(1).choice(2500, 60, replace=False):
        want = cube_value(name, "h2_over_h1", scene.slice_eps, mus[k % 50], taus[k // 50])
        if want > 0:
            assert values[k] == float(f"{want:.3g}")
        else:
            assert np.isnan(values[k])
    glyph = renderer.glyph
    for side, axis, upper in (("left", "mu", 0), ("right", "mu", 1),
                              ("bottom", "tau_ratio", 0), ("top", "tau_ratio", 1)):  # fmt: skip
        args = getattr(glyph, side).expr.args
        assert (args["columns"], args["across"], args["upper"]) == (50, axis == "tau_ratio", upper)
        np.testing.assert_allclose(args["edges"], log_edges(cube[axis].values), atol=1e-6)
    figure = scene.figure.object
    assert (figure.x_range.start, figure.x_range.end) == pytest.approx(np.log10(mus[[0, -1]]))
    assert (figure.y_range.start, figure.y_range.end) == pytest.approx(np.log10(taus[[0, -1]]))
    assert not figure.select({"type": Image})  # (no image: the rectangles alone)


def test_an_eps_move_on_the_hertz_map_sends_the_cells_codes_alone():
    """Each eps move sent the whole 177 x 227 image, 163 kB to every browser, then the cells'
    float32 values; now their uint16 codes alone."""
    explorer, document = served({"map_force": "hertz", "eps": "0.6"})
    scene = explorer.scenes["map"]
    renderer, *_ = cells_of(explorer)
    figure = scene.figure.object
    size, events = patch_bytes(document, lambda: setattr(explorer.state, "eps", 0.9))
    assert scene.figure.object is figure and scene.slice_eps == pytest.approx(0.9, abs=0.006)
    assert 5_000 < size < MOST_BYTES_A_MOVE, size
    changed = [e for e in events if getattr(e, "model", None) is renderer.data_source]
    assert [e.cols for e in changed] == [["value"]]
    # the patch carries the codes as a uint16 buffer
    message = Protocol().create("PATCH-DOC", list(events))
    content = json.loads(message.content_json)
    sent = [e for e in content["events"] if e.get("cols") == ["value"]]
    (column,) = [e["data"]["entries"] for e in sent][0]
    assert column[0] == "value" and column[1]["dtype"] == "uint16"
    _, _, after = cells_of(explorer)
    cube = twoball.load_cube("hertz-h1e4")
    want = cube["h2_over_h1"].sel(eps=scene.slice_eps).transpose("tau_ratio", "mu").values
    assert_ratios_held(after, want.ravel())


def test_the_map_cube_s_image_travels_as_codes():
    """The map cube's 81 x 73 image: uint16 codes, half its float32 bytes, at the first
    document as at an eps move."""
    explorer, document = served({"eps": "0.6"})
    figure = explorer.scenes["map"].figure.object
    assert figure.select({"type": Image}) and not figure.select({"type": Quad})
    (hover,) = figure.select({"type": HoverTool})
    assert "logs" in hover.formatters["$x"].args  # (the nearest cell looked for: CELL_JS)
    source = explorer.scenes["map"]._image_source
    assert source.data["image"][0].dtype == np.uint16
    size, _ = patch_bytes(document, lambda: setattr(explorer.state, "eps", 0.9))
    assert 81 * 73 * 2 < size < 81 * 73 * 4, size  # its codes, not its float32 values


def test_the_hertz_map_s_colours_hover_and_grey():
    """The rectangles are coloured by the colour bar's mapper from their decoded values, a
    cell without a ratio grey (NO_RATIO: hertz-h1e2 at eps 0.5 has such cells); the hover
    finds the cell under the pointer and prints its code's digits."""
    from app.delayed_map import NO_RATIO
    from app.map_browser import CELL_JS, DECODE_JS, VALUE_JS

    explorer, _ = served({"map_force": "hertz", "H": "100", "eps": "0.5"})
    scene = explorer.scenes["map"]
    renderer, codes, values = cells_of(explorer)
    figure = scene.figure.object
    (bar,) = figure.select({"type": ColorBar})
    for colour in (renderer.glyph.fill_color, renderer.glyph.line_color):
        assert colour.transform is bar.color_mapper and DECODE_JS in colour.expr.code
    assert bar.color_mapper is scene._colour_mapper and bar.color_mapper.nan_color == NO_RATIO
    assert renderer.nonselection_glyph is renderer.glyph  # (a click fades no cell)
    cube = twoball.load_cube("hertz-h1e2")["h2_over_h1"].sel(eps=0.5)
    want = cube.transpose("tau_ratio", "mu").values.ravel()
    grey = ~(want > 0)
    assert grey.sum() > 5 and (codes[grey] == NO_CODE).all()
    assert_ratios_held(values, want)
    limits = scene._colour_mapper.low, scene._colour_mapper.high
    cube_all = twoball.load_cube("hertz-h1e2")["h2_over_h1"].values
    spread = np.percentile(np.abs(np.log10(cube_all[cube_all > 0])), 98)
    assert limits == pytest.approx((10**-spread, 10**spread), rel=1e-6)  # the cube's, all eps
    (hover,) = figure.select({"type": HoverTool})
    assert hover.renderers == [renderer]
    fields = [field for _, field in hover.tooltips]
    assert fields == ["$x{custom}", "$y{custom}", "@value{custom}"]
    codes_js = {k: f.code for k, f in hover.formatters.items() if isinstance(f, CustomJSHover)}
    assert codes_js["$x"] == codes_js["$y"] == CELL_JS and codes_js["@value"] == VALUE_JS
    for at, axis in (("$x", "mu"), ("$y", "tau_ratio")):
        logs = np.log10(twoball.load_cube("hertz-h1e2")[axis].values)
        np.testing.assert_allclose(hover.formatters[at].args["logs"], logs, atol=1e-6)


def test_a_click_in_a_rectangle_picks_its_cell():
    """A click anywhere in a rectangle, even beside its edge, sets its mu and tau_ratio."""
    explorer, _ = served({"map_force": "hertz", "eps": "0.8"})
    scene = explorer.scenes["map"]
    cube = twoball.load_cube("hertz-h1e4")
    mus, taus = cube["mu"].values, cube["tau_ratio"].values
    x_edges, y_edges = log_edges(mus), log_edges(taus)
    figure = scene.figure.object
    for k in (0, 777, 1234, 2499):
        column, row = k % 50, k // 50
        for fx, fy in ((0.02, 0.98), (0.98, 0.02), (0.5, 0.5)):
            x = x_edges[column] + fx * (x_edges[column + 1] - x_edges[column])
            y = y_edges[row] + fy * (y_edges[row + 1] - y_edges[row])
            figure._trigger_event(Tap(figure, x=float(x), y=float(y)))
            state = explorer.state
            assert state.mu == pytest.approx(float(mus[column]), rel=1e-6)
            assert state.tau_ratio == pytest.approx(float(taus[row]), rel=1e-6)


def test_a_hertz_map_first_opened_off_screen_is_filled_in_place():
    """Built while another scene is on screen, then shown: the rectangles get the slice's
    codes."""
    explorer = Explorer({"scene": "drop", "eps": "0.7", "map_force": "hertz"})
    explorer.__panel__().get_root(Document())
    explorer.state.scene = "map"
    scene = explorer.scenes["map"]
    scene._redraw()
    _, _, values = cells_of(explorer)
    want = twoball.load_cube("hertz-h1e4")["h2_over_h1"].sel(eps=scene.slice_eps)
    assert_ratios_held(values, want.transpose("tau_ratio", "mu").values.ravel())
