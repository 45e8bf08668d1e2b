"""The Hertz cubes' map as one rectangle per cell (app/delayed_map.py, app/map_slices.py
``drawn_as_cells``): each rectangle lies between its neighbours' values on the log axes and
holds the value the cube holds at its mu, tau_ratio and eps, read here from the cube itself;
an eps move sends the values alone (the image it replaced sent 160 kB a move); the hover, a
click and the grey of a cell without a ratio work on the rectangles. The map cube's image is
left as it was."""

from __future__ import annotations

import json

import numpy as np
import pytest
from bokeh.document import Document
from bokeh.events import Tap
from bokeh.models import ColorBar, CustomJSHover, GlyphRenderer, HoverTool, Image, Quad
from bokeh.protocol import Protocol
from panel.io.state import set_curdoc

import twoball
from app.explorer import Explorer

# an eps move on the Hertz map: its 2500 values as float32 (10 kB), the outline and the
# colour range; the image sent 163 kB (177 x 227 float32)
MOST_BYTES_A_MOVE = 20_000


def served(query: dict) -> tuple[Explorer, Document]:
    """The explorer's page in a document as ``panel serve`` makes it (benchmarks/app_cpu.py)."""
    document = Document()
    with set_curdoc(document):
        explorer = Explorer({"scene": "map", **query})
        explorer.page().server_doc(document)
    return explorer, document


def cells_of(explorer: Explorer) -> tuple[GlyphRenderer, dict]:
    """The map's rectangles' renderer and their data (as numpy arrays)."""
    figure = explorer.scenes["map"].figure.object
    (renderer,) = [r for r in figure.select({"type": GlyphRenderer}) if isinstance(r.glyph, Quad)]
    return renderer, {k: np.asarray(v) for k, v in renderer.data_source.data.items()}


def cube_value(name: str, variable: str, eps: float, mu: float, tau_ratio: float) -> float:
    """The cube's value at one grid point, read from the cube (not the app's slices)."""
    cube = twoball.load_cube(name)
    return float(cube[variable].sel(eps=eps, mu=mu, tau_ratio=tau_ratio))


def shown(values: np.ndarray) -> np.ndarray:
    """A ratio's values as the map should colour them: float32, NaN where none (<= 0)."""
    return np.where(values > 0, values, np.nan).astype(np.float32)


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
def test_each_rectangle_is_a_cube_cell_between_its_neighbours(height, name):
    explorer, _ = served({"map_force": "hertz", "H": f"{height:g}", "eps": "0.7"})
    scene = explorer.scenes["map"]
    assert scene.slice_cube == name
    cube = twoball.load_cube(name)
    mus, taus = cube["mu"].values, cube["tau_ratio"].values
    _, data = cells_of(explorer)
    assert data["value"].size == mus.size * taus.size == 2500
    assert all(column.dtype == np.float32 for column in data.values())
    # each rectangle contains one grid value per axis, its own (the hover's mu, tau_ratio),
    # its edges half-way (in log10) to the neighbouring values, the outer ones at the ends
    for axis, values, low, high in (("mu", mus, "left", "right"),
                                    ("tau_ratio", taus, "bottom", "top")):  # fmt: skip
        logs = np.log10(values)
        index = np.abs(np.subtract.outer(data[axis].astype(float), values)).argmin(axis=1)
        np.testing.assert_allclose(data[axis], values[index], rtol=1e-6)
        inside = (logs[None, :] > data[low][:, None]) & (logs[None, :] < data[high][:, None])
        ends = (index == 0) | (index == values.size - 1)  # (their value on an edge)
        assert (inside.sum(axis=1)[~ends] == 1).all()
        below = np.log10(values[np.maximum(index - 1, 0)])
        above = np.log10(values[np.minimum(index + 1, values.size - 1)])
        first, last = index == 0, index == values.size - 1
        lows = np.where(first, logs[0], (below + logs[index]) / 2)
        highs = np.where(last, logs[-1], (above + logs[index]) / 2)
        np.testing.assert_allclose(data[low], lows, atol=1e-6)
        np.testing.assert_allclose(data[high], highs, atol=1e-6)
        assert (data[low] < data[high]).all()
    # every grid point once: the rectangles tile the map, none missing, none twice
    pairs = {(float(m), float(t)) for m, t in zip(data["mu"], data["tau_ratio"], strict=True)}
    assert len(pairs) == 2500
    # each value the cube's at that cell (a ratio without a value NaN: grey)
    for k in np.random.default_rng(1).choice(2500, 60, replace=False):
        mu = mus[np.abs(mus - data["mu"][k]).argmin()]
        tau = taus[np.abs(taus - data["tau_ratio"][k]).argmin()]
        want = cube_value(name, "h2_over_h1", scene.slice_eps, mu, tau)
        if want > 0:
            assert data["value"][k] == np.float32(want)
        else:
            assert np.isnan(data["value"][k])
    figure = scene.figure.object
    assert (figure.x_range.start, figure.x_range.end) == pytest.approx(np.log10(mus[[0, -1]]))
    assert (figure.y_range.start, figure.y_range.end) == pytest.approx(np.log10(taus[[0, -1]]))
    assert not figure.select({"type": Image})  # (no image: the rectangles alone)


def test_an_eps_move_on_the_hertz_map_sends_the_cells_values_alone():
    """Each eps move sent the whole 177 x 227 image, 163 kB to every browser; the rectangles'
    edges are sent with the figure, an eps move their values alone, float32."""
    explorer, document = served({"map_force": "hertz", "eps": "0.6"})
    scene = explorer.scenes["map"]
    renderer, before = cells_of(explorer)
    figure = scene.figure.object
    size, events = patch_bytes(document, lambda: setattr(explorer.state, "eps", 0.9))
    assert scene.figure.object is figure and scene.slice_eps == pytest.approx(0.9, abs=0.006)
    assert 10_000 < size < MOST_BYTES_A_MOVE, size
    changed = [e for e in events if getattr(e, "model", None) is renderer.data_source]
    assert [e.cols for e in changed] == [["value"]]
    # the patch carries the values as a float32 buffer, nothing of the edges
    message = Protocol().create("PATCH-DOC", list(events))
    content = json.loads(message.content_json)
    sent = [e for e in content["events"] if e.get("cols") == ["value"]]
    (column,) = [e["data"]["entries"] for e in sent][0]
    assert column[0] == "value" and column[1]["dtype"] == "float32"
    for edge in ("left", "right", "bottom", "top", "mu", "tau_ratio"):
        np.testing.assert_array_equal(renderer.data_source.data[edge], before[edge])
    _, after = cells_of(explorer)
    cube = twoball.load_cube("hertz-h1e4")
    want = cube["h2_over_h1"].sel(eps=scene.slice_eps).transpose("tau_ratio", "mu").values
    np.testing.assert_array_equal(after["value"], shown(want.ravel()))


def test_the_map_cube_s_image_is_left_as_it_was():
    explorer, document = served({"eps": "0.6"})
    figure = explorer.scenes["map"].figure.object
    assert figure.select({"type": Image}) and not figure.select({"type": Quad})
    (hover,) = figure.select({"type": HoverTool})
    assert "logs" in hover.formatters["$x"].args  # (the nearest cell looked for: CELL_JS)
    size, _ = patch_bytes(document, lambda: setattr(explorer.state, "eps", 0.9))
    assert size > 81 * 73 * 4  # its image (the map cube's is small enough)


def test_the_hertz_map_s_colours_hover_and_grey():
    """The rectangles are coloured by the colour bar's mapper, a cell without a ratio grey
    (NO_RATIO: hertz-h1e2 at eps 0.5 has such cells); the hover reads the cell's own mu,
    tau_ratio and value (no search for the nearest cell in the browser)."""
    from app.delayed_map import AXIS_VALUE_JS, CELL_JS, NO_RATIO, VALUE_JS

    explorer, _ = served({"map_force": "hertz", "H": "100", "eps": "0.5"})
    scene = explorer.scenes["map"]
    renderer, data = cells_of(explorer)
    figure = scene.figure.object
    (bar,) = figure.select({"type": ColorBar})
    for colour in (renderer.glyph.fill_color, renderer.glyph.line_color):
        assert colour.field == "value" and colour.transform is bar.color_mapper
    assert bar.color_mapper is scene._colour_mapper and bar.color_mapper.nan_color == NO_RATIO
    assert renderer.nonselection_glyph is renderer.glyph  # (a click fades no cell)
    cube = twoball.load_cube("hertz-h1e2")["h2_over_h1"].sel(eps=0.5)
    grey = ~(cube.transpose("tau_ratio", "mu").values.ravel() > 0)
    assert grey.sum() > 5 and np.isnan(data["value"][grey]).all()
    assert np.isfinite(data["value"][~grey]).all()
    limits = scene._colour_mapper.low, scene._colour_mapper.high
    cube_all = twoball.load_cube("hertz-h1e2")["h2_over_h1"].values
    spread = np.percentile(np.abs(np.log10(cube_all[cube_all > 0])), 98)
    assert limits == pytest.approx((10**-spread, 10**spread), rel=1e-6)  # the cube's, all eps
    (hover,) = figure.select({"type": HoverTool})
    assert hover.renderers == [renderer]
    fields = [field for _, field in hover.tooltips]
    assert fields == ["@mu{custom}", "@tau_ratio{custom}", "@value{custom}"]
    codes = {key: f.code for key, f in hover.formatters.items() if isinstance(f, CustomJSHover)}
    assert codes == {"@mu": AXIS_VALUE_JS, "@tau_ratio": AXIS_VALUE_JS, "@value": VALUE_JS}
    assert CELL_JS not in codes.values()


def test_a_click_in_a_rectangle_picks_its_cell():
    """A click anywhere in a rectangle, even beside its edge, sets its mu and tau_ratio."""
    explorer, _ = served({"map_force": "hertz", "eps": "0.8"})
    scene = explorer.scenes["map"]
    _, data = cells_of(explorer)
    figure = scene.figure.object
    for k in (0, 777, 1234, 2499):
        for fx, fy in ((0.02, 0.98), (0.98, 0.02), (0.5, 0.5)):
            x = data["left"][k] + fx * (data["right"][k] - data["left"][k])
            y = data["bottom"][k] + fy * (data["top"][k] - data["bottom"][k])
            figure._trigger_event(Tap(figure, x=float(x), y=float(y)))
            state = explorer.state
            assert state.mu == pytest.approx(float(data["mu"][k]), rel=1e-6)
            assert state.tau_ratio == pytest.approx(float(data["tau_ratio"][k]), rel=1e-6)


def test_a_hertz_map_first_opened_off_screen_is_filled_in_place():
    """Built blank while another scene is on screen, then shown: the same rectangles get the
    slice's values (the map's figure is not drawn again)."""
    explorer = Explorer({"scene": "drop", "eps": "0.7", "map_force": "hertz"})
    explorer.__panel__().get_root(Document())
    explorer.state.scene = "map"
    scene = explorer.scenes["map"]
    scene._redraw()
    _, data = cells_of(explorer)
    want = twoball.load_cube("hertz-h1e4")["h2_over_h1"].sel(eps=scene.slice_eps)
    want = want.transpose("tau_ratio", "mu").values.ravel()
    np.testing.assert_array_equal(data["value"], shown(want))
