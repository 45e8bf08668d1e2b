"""The map scene (app/delayed_map.py) without a browser: the slice shown is the cube's (or
computed, or a Hertz cube's) and agrees with the solver; a click sets mu and tau_ratio; an eps
move sends the new slice into the figure on screen, and what it sends is the cube's slice
(each pixel the cube's value at its mu and tau_ratio, the colour range computed here again, the
outline crossing h2/h1 = 1 between grid points). The values travel as uint16 codes
(app/map_browser.py): decoded here as the browser decodes them, each is the cube's value to
three significant digits, exactly ``float(f"{value:.3g}")``, and gets the colour its float
value got or the next one (a count's exactly)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from bokeh.document import Document
from bokeh.events import Tap
from bokeh.models import ColorBar, ColorMapper, GlyphRenderer, MultiLine
from bokeh.palettes import viridis

import twoball
from app.delayed_map import MapScene
from app.explorer import Explorer
from app.map_slices import map_cube, nearest_eps, shown_cube
from app.state import MAP_COLOURS


def rendered(query: dict) -> Explorer:
    return map_on_screen(query)[0]


def map_on_screen(query: dict) -> tuple[Explorer, MapScene]:
    explorer = Explorer({"scene": "map", **query})
    explorer.__panel__().get_root(Document())
    return explorer, explorer.scenes["map"]


def click(scene: MapScene, x: float, y: float) -> None:
    """A click on the map at (x, y) in its coordinates (log10), as Bokeh delivers it."""
    scene.figure.object._trigger_event(Tap(scene.figure.object, x=x, y=y))


def nearest_cell(cube, mu: float, tau_ratio: float) -> tuple[float, float]:
    """The cube's cell nearest (mu, tau_ratio) on the map's log axes."""
    return tuple(
        float(values[np.abs(np.log10(values) - math.log10(value)).argmin()])
        for values, value in ((cube["mu"].values, mu), (cube["tau_ratio"].values, tau_ratio))
    )


def looks(figure) -> dict:
    """How a map figure draws: its colour mapper's kind and palette, whether it has a colour
    bar, the outline's colour and width, and its tools."""
    renderers = figure.select({"type": GlyphRenderer})
    (outline,) = [r.glyph for r in renderers if isinstance(r.glyph, MultiLine)]
    mapper = figure.select_one({"type": ColorMapper})
    return {
        "mapper": (type(mapper).__name__, tuple(mapper.palette)),
        "colour bar": len(figure.select({"type": ColorBar})),
        "outline": (outline.line_color, outline.line_width),
        "tools": sorted(type(tool).__name__ for tool in figure.toolbar.tools),
    }


def on_screen(scene: MapScene):
    """The map's Bokeh figure in the page."""
    return scene.figure.object


def pixels_of(cube, eps: float, variable: str, drop=None) -> np.ndarray:
    """The slice's ``variable`` as the map should show it, found here again: rows tau_ratio,
    columns mu; the map cube's axes are evenly spaced in log10, one pixel a cell; the Hertz
    cubes' are not, and are drawn one rectangle a cell: their values flattened, rows
    tau_ratio (tests/app/test_app_map_cells.py checks where each rectangle lies)."""
    shown = cube[variable].sel(eps=eps) if drop is None else drop[variable]
    if variable in ("h2_over_h1", "h1_over_icm"):  # (no ratio where an apex is below 0)
        shown = shown.where(shown > 0)
    shown = shown.transpose("tau_ratio", "mu").values
    logs = [np.log10(cube[axis].values) for axis in ("mu", "tau_ratio")]
    if all(np.allclose(np.diff(v), np.diff(v)[0], rtol=1e-6) for v in logs):
        return shown
    return shown.ravel()


NO_CODE = 65535  # a cell without a value
RATIOS = ("h2_over_h1", "h1_over_icm")  # (coloured on a log scale)


def code_values(codes: np.ndarray) -> np.ndarray:
    """The values uint16 codes stand for, decoded as the browser decodes them (written out here
    again): 0 is 0; from 1 (positive) and from 32768 (negative) 900 codes a decade from 1e-18,
    code k of a decade the mantissa 100 + k, the value read from its digits; NO_CODE none."""
    codes = np.asarray(codes)
    assert codes.dtype == np.uint16
    values = np.full(codes.shape, np.nan)
    for code in np.unique(codes):
        if code == 0:
            values[codes == code] = 0.0
        elif code != NO_CODE:
            negative = code >= 32768
            k = int(code) - (32768 if negative else 1)
            text = f"{'-' if negative else ''}{100 + k % 900}e{k // 900 - 18 - 2}"
            values[codes == code] = float(text)
    return values


def three_digits(values: np.ndarray) -> np.ndarray:
    """Values as the hover shows them: rounded to three significant digits by Python's ``.3g``
    (NaN kept)."""
    return np.array([float(f"{v:.3g}") for v in np.ravel(values)]).reshape(np.shape(values))


def codes_on_screen(scene: MapScene) -> np.ndarray:
    """The codes the map's figure holds: its image's, or its cells' (the Hertz cubes')."""
    if scene._cell_source is not None:
        return np.asarray(scene._cell_source.data["value"])
    return scene._image_source.data["image"][0]


def values_on_screen(scene: MapScene) -> np.ndarray:
    """The values the map's figure holds, decoded as the browser decodes them."""
    return code_values(codes_on_screen(scene))


def colour_index(values: np.ndarray, low: float, high: float, colours: int, log: bool):
    """The palette index Bokeh's colour mapper gives each value (its documented rules, as
    BokehJS's Linear/LogColorMapper compute them): floor of the value's share of the range
    (of its log for a LogColorMapper) times the colours, the high limit the last colour,
    values beyond the limits the end colours (no low or high colour set); -1 for NaN."""
    with np.errstate(divide="ignore", invalid="ignore"):
        share = np.log(values / low) / np.log(high / low) if log else (values - low) / (high - low)
        index = np.clip(np.floor(share * colours), 0, colours - 1)
    index = np.where(values == high, colours - 1, index)
    return np.where(np.isnan(values), -1, index).astype(int)


def assert_codes_hold(scene: MapScene, want: np.ndarray) -> None:
    """The figure's codes stand for the values ``want`` (NaN: none) to three significant
    digits, exactly what the hover shows (``float(f"{value:.3g}")``), and each is coloured as
    its float value was or with the next shade (rounded across a band's edge); a count, whole,
    exactly as it was."""
    held = values_on_screen(scene)
    assert held.shape == want.shape
    np.testing.assert_array_equal(held, three_digits(want))  # (NaN where NaN)
    mapper = scene._colour_mapper
    rules = (mapper.low, mapper.high, len(mapper.palette), scene.variable in RATIOS)
    shift = colour_index(held, *rules) - colour_index(want.astype(float), *rules)
    assert np.abs(shift).max() <= (0 if scene.variable == "contacts_first" else 1)


def colour_range(values: np.ndarray, variable: str) -> tuple[float, float]:
    """The colour limits of cells (each computed drop once, however many pixels show it):
    a shipped cube's over all its eps, a computed slice's its own. Worked out here: a ratio
    symmetric about 1 on a log scale to its 98th percentile (at least 10**0.05), a count half a
    count beyond its extremes, else the values' range."""
    if variable in ("h2_over_h1", "h1_over_icm"):
        positive = values[values > 0]
        spread = max(float(np.percentile(np.abs(np.log10(positive)), 98)), 0.05)
        return 10**-spread, 10**spread
    if variable == "contacts_first":
        return float(values.min()) - 0.5, float(values.max()) + 0.5
    return float(values.min()), float(values.max())


def assert_outline_crosses_one(scene: MapScene) -> None:
    """The outline on screen is the current slice's: each of its vertices lies on the segment
    between two neighbouring grid points where log10(h2/h1), interpolated linearly between
    them, is 0 (as flagged: :func:`rebound_field`), to float32."""
    from app.map_slices import rebound_field

    source = scene._outline_source.data
    slice_ = scene.slice if scene.computed else None
    cube = shown_cube(scene.slice_cube).sel(eps=scene.slice_eps) if slice_ is None else slice_
    field = rebound_field(cube["delayed_rebound"], cube["h2_over_h1"])
    if not source["xs"]:
        assert (field > 0).all() or (field < 0).all()
        return
    log_mu, log_tau = np.log10(cube["mu"].values), np.log10(cube["tau_ratio"].values)
    xs, ys = (np.asarray(source[k][0], dtype=float) for k in ("xs", "ys"))
    kept = np.isfinite(xs)
    assert kept.sum() > 10
    for x, y in zip(xs[kept], ys[kept], strict=True):
        on_column = np.abs(log_mu - x).min() < 1e-5
        axis, across, at = (log_tau, y, np.abs(log_mu - x).argmin()) if on_column else (
            log_mu, x, np.abs(log_tau - y).argmin())  # fmt: skip
        line = field[:, at] if on_column else field[at, :]
        k = np.clip(np.searchsorted(axis, across) - 1, 0, axis.size - 2)
        share = (across - axis[k]) / (axis[k + 1] - axis[k])
        assert -1e-4 <= share <= 1 + 1e-4
        crossing = line[k] + share * (line[k + 1] - line[k])
        assert abs(crossing) < 1e-4 * max(abs(line[k]), abs(line[k + 1])), (x, y)


def expected(scene: MapScene) -> dict:
    """What the figure should hold for the scene's slice, worked out from the cube."""
    from app.delayed_map import RATIO_PALETTE, count_palette
    from app.map_slices import computed_slice

    variable = scene.variable
    cube = shown_cube(scene.slice_cube)
    drop = None
    if scene.computed:
        drop = computed_slice(scene.slice_eps, scene.state.height, scene.state.eps12)
    image = pixels_of(cube, scene.slice_eps, variable, drop)
    cells = (cube[variable] if drop is None else drop[variable]).values  # (all the cube's eps)
    low, high = colour_range(cells.astype(np.float32), variable)
    if variable in ("h2_over_h1", "h1_over_icm"):
        mapper = ("LogColorMapper", tuple(RATIO_PALETTE))
    elif variable == "contacts_first":
        mapper = ("LinearColorMapper", tuple(count_palette(low, high)))
    else:
        mapper = ("LinearColorMapper", tuple(viridis(256)))
    tools = ["BoxZoomTool", "HoverTool", "PanTool", "ResetTool", "SaveTool", "TapTool"]
    return {
        "image": image,
        "range": (low, high),
        "looks": {
            "mapper": mapper,
            "colour bar": 1,
            "outline": ("black", 1.5),
            "tools": sorted([*tools, "WheelZoomTool"]),
        },
    }


def sent(scene: MapScene) -> dict:
    """What the figure on screen holds now."""
    return {
        "looks": looks(on_screen(scene)),
        "image": values_on_screen(scene),
        "range": (scene._colour_mapper.low, scene._colour_mapper.high),
    }


def assert_shows_its_slice(scene: MapScene) -> None:
    """The figure on screen shows the scene's current slice: its pixels, colours, range and
    outline, worked out here from the cube."""
    held, want = sent(scene), expected(scene)
    assert held["looks"] == want["looks"]
    assert_codes_hold(scene, want["image"])
    assert held["range"] == pytest.approx(want["range"], rel=1e-5)
    assert_outline_crosses_one(scene)


@pytest.mark.parametrize("variable", list(MAP_COLOURS))
def test_an_eps_move_sends_the_new_slice_into_the_same_figure(variable):
    explorer, scene = map_on_screen({"eps": "0.6"})
    scene.variable = variable  # (a new figure)
    scene.current()
    assert_shows_its_slice(scene)
    drawn = on_screen(scene)
    before = sent(scene)["image"].copy()

    explorer.state.eps = 0.9
    assert on_screen(scene) is drawn  # the figure stayed; its models took the new slice
    assert scene.slice_eps == nearest_eps(0.9) != nearest_eps(0.6)
    assert not np.array_equal(sent(scene)["image"], before, equal_nan=True)
    assert_shows_its_slice(scene)


def test_the_hertz_map_takes_its_slices_the_same_way():
    explorer, scene = map_on_screen({"eps": "0.7", "map_force": "hertz"})
    assert_shows_its_slice(scene)
    drawn = on_screen(scene)
    explorer.state.eps = 0.95
    assert "hertz" in scene.slice_cube and on_screen(scene) is drawn
    assert_shows_its_slice(scene)


def test_another_cube_s_grid_gets_a_figure_of_its_own():
    """The Hertz cubes' axes are not the map cube's: the linear map's figure cannot take their
    slice, and a new figure spans their grid, from the outer cells' values (as the image was
    drawn, half a pixel beyond them); the linear map's image again lies half a cell beyond
    its outer cells' centres."""
    explorer, scene = map_on_screen({"eps": "0.6"})
    linear = on_screen(scene)
    explorer.state.map_force = "hertz"
    hertz = on_screen(scene)
    assert hertz is not linear
    assert_shows_its_slice(scene)
    cube = shown_cube(scene.slice_cube)
    for axis, span in (("mu", hertz.x_range), ("tau_ratio", hertz.y_range)):
        logs = np.log10(cube[axis].values)
        assert (span.start, span.end) == pytest.approx((logs[0], logs[-1]))
    explorer.state.map_force = "linear"
    back = on_screen(scene)
    assert back is not hertz and scene._cell_source is None
    for axis, corner, size, span in (("mu", "x", "dw", back.x_range),
                                     ("tau_ratio", "y", "dh", back.y_range)):  # fmt: skip
        logs = np.log10(map_cube()[axis].values)
        half = (logs[1] - logs[0]) / 2
        (start,), (width,) = (scene._image_source.data[k] for k in (corner, size))
        assert start == pytest.approx(logs[0] - half) and width == pytest.approx(
            logs[-1] - logs[0] + 2 * half)  # fmt: skip
        assert (span.start, span.end) == pytest.approx((start, start + width))


def test_map_shows_the_cube_slice_nearest_eps_as_the_solver_computes_it():
    explorer = rendered({"eps": "0.83", "scene": "map"})
    scene = explorer.scenes["map"]
    cube_eps = map_cube()["eps"].values
    nearest = cube_eps[np.abs(cube_eps - 0.83).argmin()]
    assert scene.slice_eps == nearest
    assert "eps" not in scene.slice.dims  # one slice was read, not the cube
    values = scene.slice["h2_over_h1"]
    for i, j in ((10, 20), (40, 60)):
        mu, tau = float(values["mu"][i]), float(values["tau_ratio"][j])
        direct = twoball.simulate(nearest, mu, tau, height=map_cube().attrs["height"])
        assert float(values[i, j]) == pytest.approx(direct.h2_over_h1, rel=1e-5)
    # moving mu only moves the marker: the slice is not read again
    before = scene.computations
    explorer.state.mu = 0.03
    assert scene.computations == before


def test_the_map_of_another_drop_height_and_eps12_is_computed_and_said_so():
    explorer = rendered({"eps": "0.9", "H": "2000", "eps12": "0.7", "scene": "map"})
    scene = explorer.scenes["map"]
    note = scene._note()
    assert scene.computed and "Computed for this drop" in note and "H = 2000" in note
    values = scene.slice["h2_over_h1"]
    assert values.shape == (map_cube().sizes["mu"], map_cube().sizes["tau_ratio"])
    for i, j in ((5, 70), (30, 10), (60, 45)):
        mu, tau = float(values["mu"][i]), float(values["tau_ratio"][j])
        direct = twoball.simulate(scene.slice_eps, mu, tau, height=2000.0, eps12=0.7)
        assert float(values[i, j]) == pytest.approx(direct.h2_over_h1, rel=1e-12, nan_ok=True)
    # back to the cube's drop: the shipped slice again
    explorer.state.param.update(height=map_cube().attrs["height"], eps12=None)
    scene.current()
    assert not scene.computed and "Precomputed map at" in scene._note()


def test_a_click_on_the_map_sets_mu_and_tau_ratio_and_moves_the_sliders():
    explorer = rendered({"scene": "map"})
    scene = explorer.scenes["map"]
    click(scene, math.log10(0.02), math.log10(0.15))  # the map is drawn in log10
    # the computed cell nearest the click: its drop is the one the map shows there
    mu, tau_ratio = nearest_cell(map_cube(), 0.02, 0.15)
    assert explorer.state.mu == mu and explorer.state.tau_ratio == tau_ratio
    assert mu == pytest.approx(0.02, rel=0.05) and tau_ratio == pytest.approx(0.15, rel=0.07)
    assert explorer.controls.sliders["mu"].value == pytest.approx(math.log10(mu))
    assert explorer.controls.sliders["tau_ratio"].value == pytest.approx(math.log10(tau_ratio))
    drop = twoball.simulate(0.9, mu, tau_ratio, height=map_cube().attrs["height"])
    cell = scene.slice["h2_over_h1"].sel(mu=mu, tau_ratio=tau_ratio)
    assert float(cell) == pytest.approx(drop.h2_over_h1, rel=1e-5)


def test_the_map_of_contact_counts_ticks_whole_numbers():
    """A count's colour bar has no ticks between whole numbers (it showed 2.5, 3.5)."""
    explorer = rendered({"scene": "map"})
    scene = explorer.scenes["map"]
    scene.variable = "contacts_first"
    colorbar = on_screen(scene).select_one({"type": ColorBar})
    assert colorbar.ticker.min_interval == 1 and colorbar.color_mapper is scene._colour_mapper


def _one_band_a_count(scene: MapScene) -> None:
    """The figure on screen colours each whole number of the cube with a colour of its own:
    a palette of one colour per count from the smallest to the largest of all its eps, its
    limits half a count beyond them (each count's band centred on it, where its tick is)."""
    counts = shown_cube(scene.slice_cube)["contacts_first"].values
    low, high = int(np.nanmin(counts)), int(np.nanmax(counts))
    mapper = scene._colour_mapper
    assert type(mapper).__name__ == "LinearColorMapper"
    assert (mapper.low, mapper.high) == (low - 0.5, high + 0.5)
    assert len(mapper.palette) == high - low + 1 == len(set(mapper.palette))
    # each count's band: the colour the mapper gives it is its own, one a count
    bands = [int((count - mapper.low) / (mapper.high - mapper.low) * len(mapper.palette))
             for count in range(low, high + 1)]  # fmt: skip
    assert bands == list(range(high - low + 1))


@pytest.mark.parametrize("force", ["linear", "hertz"])
def test_the_map_of_contact_counts_is_one_colour_a_count(force):
    """A count's colours were a smooth gradient (256 shades between 1 and 12 contacts, shades
    that stand for no count): a band per whole number, the same after an eps move."""
    explorer, scene = map_on_screen({"map_colour": "contacts_first", "map_force": force})
    scene.current()
    _one_band_a_count(scene)
    explorer.state.eps = 0.6 if force == "linear" else 0.55
    _one_band_a_count(scene)
    assert_shows_its_slice(scene)


def _turns(path: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """The angles (degrees) by which an outline turns at each of its vertices (those where it
    turns at all), over every piece of it (pieces separated by NaN)."""
    xs, ys = path
    cuts = np.flatnonzero(np.isnan(xs))
    turns = []
    for x, y in zip(np.split(xs, cuts), np.split(ys, cuts), strict=True):
        steps = np.diff(np.c_[x, y][np.isfinite(x)], axis=0)
        steps = steps[np.hypot(*steps.T) > 1e-12]
        headings = np.arctan2(steps[:, 1], steps[:, 0])
        turn = np.degrees(np.abs((np.diff(headings) + np.pi) % (2 * np.pi) - np.pi))
        turns.extend(turn[turn > 1e-6])
    return np.array(turns)


@pytest.mark.parametrize("cube", ["hertz-h1e4", "hertz-h1e2", "map"])
def test_the_delayed_rebound_outline_is_smooth(cube):
    """Drawn on the image's pixels, the Hertz maps' outlines followed their cells' edges (the
    cubes are evenly spaced in mu, their cells several pixels wide on the log axes): right-angle
    steps, each drawn by marching squares as two 45 degree turns, the median turn 45 degrees.
    Contoured on the cube's own points through log10(h2/h1), an outline bends a little at
    each vertex (a median under 10 degrees), and its vertices lie where the ratio crosses 1
    between two points, not half-way between them."""
    from app.map_slices import nearest_eps, outline_of, shown_cube

    eps = nearest_eps(0.9, cube)
    path = outline_of(cube, eps, None)
    turns = _turns(path)
    assert turns.size > 100 and np.median(turns) < 10, np.median(turns)
    # each vertex on the segment between two neighbouring points, most not at its middle
    shown = shown_cube(cube).sel(eps=eps)
    axes = [np.log10(shown[name].values) for name in ("mu", "tau_ratio")]
    middles = [(axis[1:] + axis[:-1]) / 2 for axis in axes]
    at_middle = np.zeros(0, dtype=bool)
    for values, axis, middle in zip(path, axes, middles, strict=True):
        values = values[np.isfinite(values)]
        gap = np.diff(axis).min()
        on_point = np.abs(np.subtract.outer(values, axis)).min(axis=1) < 1e-6 * gap
        halfway = np.abs(np.subtract.outer(values, middle)).min(axis=1) < 1e-6 * gap
        at_middle = halfway if at_middle.size == 0 else at_middle | halfway
        assert on_point.any()
    assert at_middle.mean() < 0.5, at_middle.mean()


def test_the_hertz_map_shows_the_shipped_hertz_cube_nearest_the_drop_height():
    """The map's Hertz force: a slice of hertz-h1e4 (or h1e2, whichever H is nearer the drop's)
    at the eps nearest the drop's, each cell the library's Hertz two-ball drop; the note says
    H is in the Hertz unit and tau_ratio counts the Hertz floor contact; the URL carries it."""
    from app.map_slices import shown_cube
    from app.state import read_query, url_query

    explorer = rendered({"eps": "0.83", "scene": "map", "map_force": "hertz"})
    scene = explorer.scenes["map"]
    assert scene.cube_name() == "hertz-h1e4"  # the drop's H = 1e4
    cube = shown_cube("hertz-h1e4")
    cube_eps = cube["eps"].values
    assert scene.slice_eps == cube_eps[np.abs(cube_eps - 0.83).argmin()]
    values = scene.slice["h2_over_h1"]
    assert values.dims == ("mu", "tau_ratio") and values.shape == (50, 50)
    for i, j in ((3, 40), (20, 10), (45, 45)):
        mu, tau = float(values["mu"][i]), float(values["tau_ratio"][j])
        direct = twoball.simulate_stack(
            [mu], scene.slice_eps, tau, height=cube.attrs["height"], force="hertz"
        )
        assert float(values[i, j]) == pytest.approx(direct.h2 / direct.h1, rel=1e-6)
    note = scene._note()
    assert "Hertz force" in note and "Hertz length unit" in note and "hertz-h1e4" in note
    assert "Hertz floor contact" in note
    assert "use the **linear** force" in note  # where a click on it leads (the drop scenes)
    assert "linear" not in scene._note() or scene.state.map_force == "hertz"
    assert url_query(explorer.state)["map_force"] == "hertz"
    assert read_query(url_query(explorer.state), explorer.state)[0]["map_force"] == "hertz"
    # every rectangle is one of the slice's cells (none interpolated), rows tau_ratio
    shown = values.where(values > 0).transpose("tau_ratio", "mu").values.ravel()
    assert_codes_hold(scene, shown)
    # a drop nearer H = 100: the other cube; a click still sets mu and tau_ratio
    explorer.state.height = 300.0
    scene.current()
    assert scene.cube_name() == "hertz-h1e2" and "hertz-h1e2" in scene._note()
    click(scene, math.log10(0.05), math.log10(0.3))
    mu, tau_ratio = nearest_cell(shown_cube("hertz-h1e2"), 0.05, 0.3)
    assert (explorer.state.mu, explorer.state.tau_ratio) == (mu, tau_ratio)
    # back to linear: the map cube again
    explorer.state.map_force = "linear"
    scene.current()
    assert scene.cube_name() == "map" and "Hertz" not in scene._note()
    assert "map_force" not in url_query(explorer.state)


def test_a_map_first_opened_from_another_scene_shows_its_slice():
    """Built when its tab is first chosen, the map's figure is drawn before the scene is on
    screen (a blank frame), then given the slice."""
    explorer = Explorer({"scene": "drop", "eps": "0.7"})
    explorer.__panel__().get_root(Document())
    explorer.state.scene = "map"
    scene = explorer.scenes["map"]
    scene._redraw()  # (what the page does on the next tick)
    assert scene.active and scene.slice_eps == nearest_eps(0.7)
    assert_shows_its_slice(scene)


def test_the_map_s_colour_travels_in_a_link():
    """The quantity coloured is in the URL (map_colour), read back from a link, kept out of it
    at its default and on other scenes, and a bad one is reported (a new user's shared link
    reopened on h2/h1)."""
    from app.state import read_query, url_query

    explorer, scene = map_on_screen({"map_colour": "contacts_first"})
    assert scene.variable == "contacts_first" and scene.choice.value == "contacts_first"
    assert url_query(explorer.state)["map_colour"] == "contacts_first"
    scene.choice.value = "h1_over_icm"  # chosen in the page
    assert explorer.state.map_colour == scene.variable == "h1_over_icm"
    assert url_query(explorer.state)["map_colour"] == "h1_over_icm"
    explorer.state.map_colour = "h2_over_h1"  # (back to the default: a short link)
    assert scene.variable == scene.choice.value == "h2_over_h1"
    assert "map_colour" not in url_query(explorer.state)
    explorer.state.param.update(map_colour="h2_over_drop", scene="drop")
    assert "map_colour" not in url_query(explorer.state)
    values, messages = read_query({"map_colour": "speed"}, explorer.state)
    assert "map_colour" not in values and messages[0].startswith("URL map_colour: must be one")


def test_the_map_s_labels_say_what_a_class_reads_not_the_library_s_names():
    """A variable's label is the cube's long name without the library's name for it in
    parentheses (the count's colour bar read "... (Result.contacts_first[1])")."""
    from app.map_slices import MAP_COLOURS, map_cube, variable_label

    long_name = map_cube()["contacts_first"].attrs["long_name"]
    assert "(Result." in long_name  # (the cube's own, for the library's users)
    label = variable_label("contacts_first")
    assert label == long_name.split(" (Result.")[0] and "Result" not in label
    for variable in MAP_COLOURS:
        assert "Result." not in variable_label(variable)


def test_the_choice_and_the_colour_bar_name_a_variable_alike():
    """A new user met "h1 / h_ICM" and "X2(0)", and a count named one way in the choice and
    another on the bar: one label, in words, for both."""
    from app.map_slices import MAP_COLOURS, shown_label

    explorer, scene = map_on_screen({})
    for variable in MAP_COLOURS:
        scene.choice.value = variable
        (bar,) = on_screen(scene).select({"type": ColorBar})
        (label,) = [k for k, v in scene.choice.options.items() if v == variable]
        assert bar.title == label == shown_label(variable)
        assert "X2(0)" not in label and "h_ICM" not in label


@pytest.mark.parametrize("name", ["map", "hertz-h1e2", "hertz-h1e4", "computed"])
def test_the_codes_hold_every_value_to_the_hover_s_three_digits(name):
    """Every value of every variable the map shows (a whole shipped cube, all its eps, or a
    slice computed for another drop), negative ones too, is coded as exactly the number the
    hover prints, ``float(f"{value:.3g}")``; the counts are their whole numbers."""
    from app.map_slices import computed_slice, encoded

    cube = computed_slice(0.9, 2000.0, 0.7) if name == "computed" else shown_cube(name)
    for variable in MAP_COLOURS:
        values = cube[variable].values
        held = code_values(encoded(values))
        np.testing.assert_array_equal(held, three_digits(values), err_msg=variable)
        if variable == "contacts_first":
            assert (held == values).all() and values.max() < 1000
    assert (cube["h2_over_drop"].values < 0).any()  # (negative values coded too)


def test_the_codes_round_as_the_hover_and_clip_beyond_their_decades():
    """Zero, a rounding up to the next decade, both signs, no value; beyond 9.99e17 or below
    1e-18 the largest or smallest code of the sign."""
    from app.map_slices import encoded

    values = np.array([0.0, 9.996, -9.996e-5, 0.012345, 123456.0, np.nan, np.inf, 1e-300, -3e40])
    held = code_values(encoded(values))
    np.testing.assert_array_equal(held[:6], three_digits(values[:6]))
    assert held[6] != held[6] and (held[7], held[8]) == (1e-18, -9.99e17)


def test_the_codes_worked_out_in_numpy_round_as_python_does_at_ties_and_decade_ends():
    """The codes are worked out in NumPy: values over every decade, both signs, and those
    where binary arithmetic and Python's decimal rounding could part (mantissas exactly
    halfway, 100.5 or 2.675e-3, values that round up into the next decade, 9.995, 999.5) are
    coded as exactly the number the hover prints."""
    from app.map_slices import encoded

    rng = np.random.default_rng(7)
    spread = 10 ** rng.uniform(-17.9, 17.9, 20000) * rng.choice([-1.0, 1.0], 20000)
    mantissas = np.arange(100, 1000, dtype=float)
    ties = np.concatenate([(mantissas + 0.5) * 10.0**k for k in (-7, -3, 0, 2)])
    edges = np.array([9.995, 999.5, 0.09995, 2.675e-3, 1.005, 99.95, -9.995e-4, 1e-18, 9.99e17])
    values = np.concatenate([spread, ties, -ties, mantissas, edges])
    np.testing.assert_array_equal(code_values(encoded(values)), three_digits(values))


def test_a_ratio_with_an_apex_below_zero_is_grey_not_a_colour_of_the_scale():
    """h2/h1 is negative where the first apex lies below 0 (h1 = -134, h2 = 9329: a strong
    delayed rebound): drawn dark blue, it read as h2 far below h1. It is no ratio: NaN in the
    image, grey, and the note says what grey means."""
    from app.delayed_map import NO_RATIO

    explorer, scene = map_on_screen({"eps": "0.9"})
    values = scene.slice["h2_over_h1"].transpose("tau_ratio", "mu").values
    below = values <= 0
    assert below.any()  # (five such cells at eps 0.9)
    image = scene._image_source.data["image"][0]
    assert (image[below] == NO_CODE).all() and (image[~below] != NO_CODE).all()
    assert scene._colour_mapper.nan_color == NO_RATIO
    assert "grey: no ratio (an apex below 0" in scene._note()
    scene.variable = "h1_over_drop"  # (not a ratio of two apexes: its values drawn as they are)
    scene.current()
    assert (scene._image_source.data["image"][0] != NO_CODE).all()
    assert "grey" not in scene._note()


def test_a_slice_s_colours_are_the_cube_s_whatever_eps():
    """Each slice had its own colour range (h2/h1 0.15-6.6 at eps 0.9, 0.05-20 at 0.5): one
    colour meant two values. Every slice of a shipped cube now has the cube's."""
    explorer, scene = map_on_screen({"eps": "0.9"})
    first = (scene._colour_mapper.low, scene._colour_mapper.high)
    explorer.state.eps = 0.5
    assert scene.slice_eps == 0.5
    assert (scene._colour_mapper.low, scene._colour_mapper.high) == first
    assert first == pytest.approx(colour_range(map_cube()["h2_over_h1"].values, "h2_over_h1"))


def test_a_drop_whose_eps_lies_outside_the_cube_gets_its_own_slice():
    """Below eps 0.5 the map kept showing eps 0.5, whose delayed rebound the Drop tab did not
    show. The drop's eps (to 0.01) is computed and said so; a Hertz map, never computed, says
    that the drop's eps lies outside it."""
    explorer, scene = map_on_screen({"eps": "0.164"})
    assert scene.computed and scene.slice_eps == pytest.approx(0.16)
    note = scene._note()
    assert "Computed for this drop at **eps = 0.16**" in note and "run from eps = 0.5 to 1" in note
    values = scene.slice["h2_over_h1"]
    for i, j in ((5, 70), (30, 10), (60, 45)):
        mu, tau = float(values["mu"][i]), float(values["tau_ratio"][j])
        direct = twoball.simulate(0.16, mu, tau, height=map_cube().attrs["height"])
        assert float(values[i, j]) == pytest.approx(direct.h2_over_h1, rel=1e-12, nan_ok=True)
    assert_shows_its_slice(scene)
    assert scene.download.filename == "map-computed-h2_over_h1-eps0.16.csv"
    explorer.state.eps = 0.05  # (below 0.1 a slice took the server 0.8 s and more)
    scene.current()
    assert not scene.computed and scene.slice_eps == 0.5
    assert "maps are computed down to eps = 0.1" in scene._note()
    explorer.state.param.update(eps=0.164, map_force="hertz")
    scene.current()
    assert not scene.computed and scene.slice_eps == 0.5
    assert "**The current eps = 0.164 lies outside the map**" in scene._note()
    assert "the Hertz maps are not computed here" in scene._note()
    assert scene.download.filename == f"map-{scene.slice_cube}-h2_over_h1-eps0.5.csv"


def test_the_note_gives_the_value_at_the_star():
    """A phone's tap shows no hover, and a projected hover is too small for a room: the note
    gives the value of the computed cell at the star, the one a drop there has."""
    explorer, scene = map_on_screen({"eps": "0.9"})
    click(scene, math.log10(0.0302), math.log10(0.0205))
    mu, tau_ratio = explorer.state.mu, explorer.state.tau_ratio
    drop = twoball.simulate(0.9, mu, tau_ratio, height=map_cube().attrs["height"])
    assert (
        f"At the star (mu = {mu:.3g}, tau_d/tau_f = {tau_ratio:.3g}): "
        f"**h2 / h1 = {drop.h2_over_h1:.3f}**." in scene._note()
    )
    explorer.state.mu = 5.0  # (beyond the map's mu: no value)
    assert "At the star" not in scene._note()


def test_the_note_says_plainly_when_the_star_is_off_the_map():
    """The mu slider runs to 10, the map to 1: at mu = 5 the star lay off the map and the note's
    last line said only "lies outside the map (0.001 to 1): the star is off the map". The note
    opens with it: no star, past which edge, what the map shows (an upper ball at most as
    heavy as the lower one) and how to bring the star back; a drop on the map says none of it."""
    explorer, scene = map_on_screen({"eps": "0.9", "mu": "5", "tau_ratio": "0.0002"})
    note = scene._note()
    first, second = note.split("  \n")[:2]
    assert first.startswith("**No star: mu = 5 is off the map**, past its right edge")
    assert "at most as heavy as the lower one; this one is 5 times heavier" in first
    assert "set mu to 1 or less to see it on the map" in first
    assert second.startswith("**No star: tau_d/tau_f = 0.0002 is off the map**, past its bottom")
    assert "At the star" not in note
    explorer.state.param.update(mu=0.01, tau_ratio=0.01)
    assert "No star" not in scene._note() and "At the star" in scene._note()
