"""The map scene (app/delayed_map.py) without a browser: the slice shown is the cube's (or
computed, or a Hertz cube's) and agrees with the solver; a click sets mu and tau_ratio; an eps
move sends the new slice into the figure HoloViews drew, and what it sends is what HoloViews
itself draws for that slice."""

from __future__ import annotations

import math

import holoviews as hv
import numpy as np
import pytest
from bokeh.document import Document
from bokeh.models import ColorBar, ColorMapper, GlyphRenderer, Image, MultiLine

import twoball
from app.delayed_map import MapScene, map_cube, nearest_eps
from app.explorer import Explorer


def rendered(query: dict) -> Explorer:
    return map_on_screen(query)[0]


def map_on_screen(query: dict) -> tuple[Explorer, MapScene]:
    explorer = Explorer({"scene": "map", **query})
    explorer.__panel__().get_root(Document())
    return explorer, explorer.scenes["map"]


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
    ((plot, _),) = scene.figure._plots.values()
    return plot.state


def drawn_by_holoviews(scene: MapScene) -> dict:
    """The scene's current slice rendered by HoloViews from scratch: the image's values, the
    colour mapper's range and the outline's paths, and how it draws them."""
    figure = hv.render(scene._image(True, scene.variable) * scene._outline(True))
    renderers = figure.select({"type": GlyphRenderer})
    (image,) = [r.data_source for r in renderers if isinstance(r.glyph, Image)]
    (outline,) = [r.data_source for r in renderers if isinstance(r.glyph, MultiLine)]
    mapper = figure.select_one({"type": ColorMapper})
    return {
        "image": image.data["image"][0],
        "range": (mapper.low, mapper.high),
        "xs": list(outline.data["xs"]),
        "ys": list(outline.data["ys"]),
        "looks": looks(figure),
    }


def sent(scene: MapScene) -> dict:
    """What the figure on screen holds now."""
    return {
        "looks": looks(on_screen(scene)),
        "image": scene._image_source.data["image"][0],
        "range": (scene._colour_mapper.low, scene._colour_mapper.high),
        "xs": list(scene._outline_source.data["xs"]),
        "ys": list(scene._outline_source.data["ys"]),
    }


def assert_same(held: dict, drawn: dict) -> None:
    assert held["looks"] == drawn["looks"]
    assert held["image"].dtype == drawn["image"].dtype
    np.testing.assert_array_equal(held["image"], drawn["image"])
    assert held["range"] == pytest.approx(drawn["range"], rel=1e-6)
    assert len(held["xs"]) == len(drawn["xs"])
    for mine, theirs in zip(held["xs"] + held["ys"], drawn["xs"] + drawn["ys"], strict=True):
        np.testing.assert_array_equal(mine, theirs)


@pytest.mark.parametrize("variable", ["h2_over_h1", "h1_over_drop", "contacts_first"])
def test_an_eps_move_sends_the_slice_holoviews_would_draw_without_redrawing(variable):
    explorer, scene = map_on_screen({"eps": "0.6"})
    scene.variable = variable  # (a new figure, drawn by HoloViews)
    scene.current()
    before = sent(scene)["image"].copy()
    reframes = []
    scene.param.watch(lambda event: reframes.append(event), "reframe")

    explorer.state.eps = 0.9
    assert not reframes  # the figure's frame stayed; its models took the new slice
    assert scene.slice_eps == nearest_eps(0.9) != nearest_eps(0.6)
    held = sent(scene)
    assert not np.array_equal(held["image"], before, equal_nan=True)
    assert_same(held, drawn_by_holoviews(scene))


def test_the_hertz_map_takes_its_slices_the_same_way():
    explorer, scene = map_on_screen({"eps": "0.7", "map_force": "hertz"})
    explorer.state.eps = 0.95
    assert "hertz" in scene.slice_cube
    assert_same(sent(scene), drawn_by_holoviews(scene))


def test_a_slice_on_another_grid_is_drawn_again_by_holoviews():
    """The pushed image must fit the drawn one; a slice that does not (here: a figure drawn
    from a blank of another shape) makes HoloViews draw the frame again."""
    explorer, scene = map_on_screen({"eps": "0.6"})
    scene._image_source.data = {**scene._image_source.data, "image": [np.ones((3, 3))]}
    reframes = []
    scene.param.watch(lambda event: reframes.append(event), "reframe")
    explorer.state.eps = 0.9
    assert len(reframes) == 1


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
    scene.tap.event(x=math.log10(0.02), y=math.log10(0.15))  # the map is drawn in log10
    assert explorer.state.mu == pytest.approx(0.02)
    assert explorer.state.tau_ratio == pytest.approx(0.15)
    assert explorer.controls.sliders["mu"].value == pytest.approx(math.log10(0.02))
    assert explorer.controls.sliders["tau_ratio"].value == pytest.approx(math.log10(0.15))


def test_the_map_of_contact_counts_ticks_whole_numbers():
    """A count's colour bar has no ticks between whole numbers (it showed 2.5, 3.5)."""
    explorer = rendered({"scene": "map"})
    scene = explorer.scenes["map"]
    scene.variable = "contacts_first"
    image = scene._image(scene.revision, "contacts_first")
    colorbar = hv.render(image).select_one({"type": ColorBar})
    assert colorbar.ticker.min_interval == 1


def _one_band_a_count(scene: MapScene) -> None:
    """The figure on screen colours each whole number of the slice with a colour of its own:
    a palette of one colour per count from the smallest to the largest, its limits half a
    count beyond them (each count's band centred on it, where its tick is)."""
    counts = scene.slice["contacts_first"].values
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
    that stand for no count): a band per whole number, also after an eps move (its range of
    counts changes)."""
    explorer, scene = map_on_screen({"map_colour": "contacts_first", "map_force": force})
    scene.current()
    _one_band_a_count(scene)
    explorer.state.eps = 0.3 if force == "linear" else 0.55
    _one_band_a_count(scene)
    assert_same(sent(scene), drawn_by_holoviews(scene))


def _turns(path: hv.Contours) -> np.ndarray:
    """The angles (degrees) by which an outline turns at each of its vertices (those where it
    turns at all), over every piece of it (pieces separated by NaN)."""
    xs, ys = path.dimension_values(0), path.dimension_values(1)
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
    from app.delayed_map import nearest_eps, outline_of, shown_cube

    eps = nearest_eps(0.9, cube)
    path = outline_of(cube, eps, None)
    turns = _turns(path)
    assert turns.size > 100 and np.median(turns) < 10, np.median(turns)
    # each vertex on the segment between two neighbouring points, most not at its middle
    shown = shown_cube(cube).sel(eps=eps)
    axes = [np.log10(shown[name].values) for name in ("mu", "tau_ratio")]
    middles = [(axis[1:] + axis[:-1]) / 2 for axis in axes]
    at_middle = np.zeros(0, dtype=bool)
    for values, axis, middle in zip(path.columns().values(), axes, middles, strict=False):
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
    from app.delayed_map import shown_cube
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
    # every pixel of the image is one of the slice's cells (none interpolated)
    shown = scene._image(True, "h2_over_h1").dimension_values(2)
    assert np.isin(shown[np.isfinite(shown)], values.values).all()
    # a drop nearer H = 100: the other cube; a click still sets mu and tau_ratio
    explorer.state.height = 300.0
    scene.current()
    assert scene.cube_name() == "hertz-h1e2" and "hertz-h1e2" in scene._note()
    scene.tap.event(x=math.log10(0.05), y=math.log10(0.3))
    assert explorer.state.mu == pytest.approx(0.05)
    assert explorer.state.tau_ratio == pytest.approx(0.3)
    # back to linear: the map cube again
    explorer.state.map_force = "linear"
    scene.current()
    assert scene.cube_name() == "map" and "Hertz" not in scene._note()
    assert "map_force" not in url_query(explorer.state)


def test_a_map_first_opened_from_another_scene_shows_its_slice():
    """Built when its tab is first chosen, the map's figure is drawn before the scene is on
    screen (a blank frame), then given the slice: what HoloViews would draw for it."""
    explorer = Explorer({"scene": "drop", "eps": "0.7"})
    explorer.__panel__().get_root(Document())
    explorer.state.scene = "map"
    scene = explorer.scenes["map"]
    scene._redraw()  # (what the page does on the next tick)
    assert scene.active and scene.slice_eps == nearest_eps(0.7)
    assert_same(sent(scene), drawn_by_holoviews(scene))


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
    from app.delayed_map import MAP_COLOURS, map_cube, variable_label

    long_name = map_cube()["contacts_first"].attrs["long_name"]
    assert "(Result." in long_name  # (the cube's own, for the library's users)
    label = variable_label("contacts_first")
    assert label == long_name.split(" (Result.")[0] and "Result" not in label
    for variable in MAP_COLOURS:
        assert "Result." not in variable_label(variable)
