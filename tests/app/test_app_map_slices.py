"""The map scene's slices (app/delayed_map.py): an eps move sends the new slice into the figure
HoloViews drew, and what it sends is what HoloViews itself draws for that slice."""

from __future__ import annotations

import holoviews as hv
import numpy as np
import pytest
from bokeh.document import Document
from bokeh.models import ColorMapper, GlyphRenderer, Image, MultiLine

from app.delayed_map import MapScene, nearest_eps
from app.explorer import Explorer


def map_on_screen(query: dict) -> tuple[Explorer, MapScene]:
    explorer = Explorer({"scene": "map", **query})
    explorer.__panel__().get_root(Document())
    return explorer, explorer.scenes["map"]


def drawn_by_holoviews(scene: MapScene) -> dict:
    """The scene's current slice rendered by HoloViews from scratch: the image's values, the
    colour mapper's range and the outline's paths."""
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
    }


def sent(scene: MapScene) -> dict:
    """What the figure on screen holds now."""
    return {
        "image": scene._image_source.data["image"][0],
        "range": (scene._colour_mapper.low, scene._colour_mapper.high),
        "xs": list(scene._outline_source.data["xs"]),
        "ys": list(scene._outline_source.data["ys"]),
    }


def assert_same(held: dict, drawn: dict) -> None:
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
