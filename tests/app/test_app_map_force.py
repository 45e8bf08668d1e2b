"""The map's slices and force switch, and the Stack scene's "advanced" eps per contact, in
Chromium: an eps move shows the new slice, the switch shows the shipped Hertz cube and says so,
the URL follows, a bad entry is reported and the page goes on. Screenshots go to
test-artifacts/map_force/."""

from __future__ import annotations

import re

import numpy as np
import pytest
from appdriver import (
    deep_query,
    fingerprint,
    open_page,
    page_query,
    press_slider,
    sources_with,
    wait_for_change,
)
from playwright.sync_api import expect

from app.map_slices import cube_colour_limits, eps_slice, nearest_eps, slice_image
from app.scene import on_screen

pytestmark = pytest.mark.browser
# the map's image (its values, flattened) and its colour mapper's range, in the browser
IMAGE_JS = """() => {
  const models = [...Bokeh.documents[0].all_models];
  const image = models.find((m) => m.constructor.__name__ === "ColumnDataSource"
    && (m.data instanceof Map ? m.data.has("image") : "image" in m.data));
  const data = image.data instanceof Map ? image.data.get("image") : image.data.image;
  const mapper = models.find((m) => m.constructor.__name__.endsWith("ColorMapper"));
  return [Array.from(data[0], (v) => (Number.isNaN(v) ? null : v)), [mapper.low, mapper.high],
          mapper.palette, models.filter((m) => m.constructor.__name__ === "ColorBar").length];
}"""


def test_an_eps_move_shows_the_new_slice_in_the_browser(browser, app_server, artifacts):
    """The map's eps move changes the figure's image, colour range and outline in place
    (app/delayed_map.py, ``_push_slice``): the browser shows the slice the cube holds."""
    base, _ = app_server
    folder = artifacts / "map_force"
    folder.mkdir(exist_ok=True)
    context, page, errors = open_page(browser, f"{base}/app?scene=map&eps=0.6")
    try:
        expect(page.get_by_text("at eps = 0.6 (nearest").first).to_be_visible(timeout=60_000)
        assert press_slider(page, "eps", key="End") > 0  # eps to its highest: plots changed
        eps = nearest_eps(float(page.locator(".bk-slider-value").first.inner_text()))
        expect(page.get_by_text(f"at eps = {eps:g} (nearest").first).to_be_visible()
        page.wait_for_timeout(500)
        limits = cube_colour_limits("map", "h2_over_h1")  # (every slice's: the cube's)
        (_, _, expected), (low, high) = slice_image(
            eps_slice(eps, "h2_over_h1"), "h2_over_h1", limits
        )
        drawn, mapped, _, _ = page.evaluate(IMAGE_JS)
        np.testing.assert_array_equal(np.array(drawn, dtype=float), on_screen(expected).ravel())
        assert mapped == pytest.approx([low, high])
        (outline,) = sources_with(page, "xs", "ys")
        assert len(outline["xs"]) == 1
        page.screenshot(path=folder / "map_eps_moved.png", full_page=True)
        assert errors == []
    finally:
        context.close()


def test_a_map_opened_from_its_tab_is_the_map_a_link_opens(browser, app_server, artifacts):
    """Built off screen and drawn blank, then given its slice: the same values, colours and
    colour bar as the map a link opens (a new user saw it blue, without its red, from the
    tab)."""
    base, _ = app_server
    folder = artifacts / "map_force"
    folder.mkdir(exist_ok=True)
    shown = {}
    for way in ("link", "tab"):
        url = f"{base}/app?eps=0.9" + ("&scene=map" if way == "link" else "")
        context, page, errors = open_page(browser, url)
        try:
            if way == "tab":
                page.locator(".bk-tab", has_text="Delayed-rebound map").click()
            expect(page.get_by_text("at eps = 0.9 (nearest").first).to_be_visible(timeout=60_000)
            page.wait_for_timeout(1500)
            shown[way] = page.evaluate(IMAGE_JS)
            page.screenshot(path=folder / f"map_from_{way}.png")
            assert errors == []
        finally:
            context.close()
    assert shown["tab"] == shown["link"]
    assert shown["tab"][3] == 1  # its colour bar


def test_the_map_switches_to_the_hertz_cube(browser, app_server, artifacts):
    base, _ = app_server
    folder = artifacts / "map_force"
    folder.mkdir(exist_ok=True)
    context, page, errors = open_page(browser, f"{base}/app?scene=map")
    try:
        expect(page.get_by_text("Precomputed map at").first).to_be_visible(timeout=60_000)
        before = fingerprint(page)
        page.get_by_role("button", name="hertz").click()
        expect(page.get_by_text("Hertz length unit").first).to_be_visible(timeout=60_000)
        expect(page.get_by_text("hertz-h1e4").first).to_be_visible()
        expect(page.get_by_text("counts the Hertz floor contact time").first).to_be_visible()
        wait_for_change(page, before)  # the image is the Hertz cube's
        # the URL is written shortly after a change (0.3 s, then the patch's way back)
        expect(page).to_have_url(re.compile(r"[?&]map_force=hertz"), timeout=10_000)
        assert page_query(page)["map_force"] == "hertz"
        page.screenshot(path=folder / "map_hertz.png", full_page=True)
        page.get_by_role("button", name="linear").click()
        expect(page.get_by_text("Precomputed map at").first).to_be_visible(timeout=60_000)
        expect(page).not_to_have_url(re.compile("map_force"), timeout=10_000)
        assert "map_force" not in page_query(page)
        assert errors == []
    finally:
        context.close()


def test_the_stack_scene_takes_eps_per_contact_under_advanced(browser, app_server, artifacts):
    base, _ = app_server
    folder = artifacts / "map_force"
    folder.mkdir(exist_ok=True)
    context, page, errors = open_page(browser, f"{base}/app?scene=stack&N=8&ratio=0.3")
    try:
        expect(page.get_by_text("8 balls, linear force")).to_be_visible(timeout=60_000)
        page.get_by_text("advanced: eps per contact").click()
        entry = page.get_by_placeholder("e.g. 0.9, 0.8, 0.7")
        entry.fill("0.9, 0.8")
        entry.press("Enter")
        expect(page.get_by_text("give 8 values for 8 balls")).to_be_visible(timeout=60_000)
        entry.fill("0.9,0.8,0.7,0.6,0.5,0.9,0.8,0.7")
        entry.press("Enter")
        expect(page.get_by_text("eps per contact 0.9, 0.8, 0.7")).to_be_visible(timeout=60_000)
        expect(page.get_by_text("give 8 values for 8 balls")).to_be_hidden()
        page.wait_for_timeout(800)
        assert page_query(page)["eps_contacts"] == "0.9,0.8,0.7,0.6,0.5,0.9,0.8,0.7"
        page.screenshot(path=folder / "stack_eight_advanced.png", full_page=True)
        assert errors == []
    finally:
        context.close()


# the labels the map's x axis formatter gives ticks (log10 values), in the browser
TICK_LABELS_JS = """(ticks) => {
  const models = [...Bokeh.documents[0].all_models];
  const formatter = models.find((m) => m.constructor.__name__ === "CustomJSTickFormatter"
    && m.code.includes("decade"));
  return formatter.doFormat(ticks, {loc: 0});
}"""


def test_the_map_s_axes_label_decades_and_zoomed_1_2_5(browser, app_server):
    """Over more than two decades the map's axes label the powers of ten alone (labelling 1, 2
    and 5 each, a projector's narrow map dropped 0.01 and 0.1 for lack of room); zoomed
    closer, 2 and 5 are labelled too (a zoomed map had kept one label per axis, or none)."""
    import math

    base, _ = app_server
    context, page, errors = open_page(browser, f"{base}/app?scene=map")
    try:
        expect(page.get_by_text("Precomputed map at").first).to_be_visible(timeout=60_000)
        whole = [math.log10(m * 10.0**d) for d in (-3, -2, -1) for m in (1, 2, 5)] + [0.0]
        labels = page.evaluate(TICK_LABELS_JS, whole)
        assert labels == ["0.001", "", "", "0.01", "", "", "0.1", "", "", "1"], labels
        zoomed = [math.log10(v) for v in (0.01, 0.02, 0.05, 0.1, 0.2)]
        assert page.evaluate(TICK_LABELS_JS, zoomed) == ["0.01", "0.02", "0.05", "0.1", "0.2"]
        assert errors == []
    finally:
        context.close()


# where a point of the Hertz map (log10 mu, log10 tau_ratio) lies in the page, in px
CELL_POINT_JS = """([x, y]) => {
  const view = [...Bokeh.index.all_views()].find((v) => v.model.constructor.__name__ === "Figure"
    && v.model.renderers.some((r) => r.glyph && r.glyph.constructor.__name__ === "Quad"));
  const box = view.el.getBoundingClientRect();
  return [box.left + view.frame.x_scale.compute(x), box.top + view.frame.y_scale.compute(y)];
}"""


def test_the_hertz_map_s_cells_take_an_eps_move_and_hover(browser, app_server, artifacts):
    """The Hertz map's rectangles (one a cell, app/map_slices.py ``drawn_as_cells``): an eps
    move gives them the new slice's values, read here from the cube, their edges kept; the
    hover over a cell gives its mu, tau_d/tau_f and value."""
    import math

    import twoball

    base, _ = app_server
    folder = artifacts / "map_force"
    folder.mkdir(exist_ok=True)
    context, page, errors = open_page(browser, f"{base}/app?scene=map&map_force=hertz&eps=0.6")
    cube = twoball.load_cube("hertz-h1e4")
    try:
        expect(page.get_by_text("Hertz length unit").first).to_be_visible(timeout=60_000)
        (before,) = sources_with(page, "left", "right", "bottom", "top", "value")
        assert press_slider(page, "eps", key="End") > 0
        eps = nearest_eps(float(page.locator(".bk-slider-value").first.inner_text()), "hertz-h1e4")
        expect(page.get_by_text(f"at eps = {eps:g} (nearest").first).to_be_visible()
        page.wait_for_timeout(500)
        (after,) = sources_with(page, "left", "right", "bottom", "top", "value")
        for edge in ("left", "right", "bottom", "top"):
            assert after[edge] == before[edge]
        want = cube["h2_over_h1"].sel(eps=eps).transpose("tau_ratio", "mu").values.ravel()
        want = np.where(want > 0, want, np.nan).astype(np.float32)
        np.testing.assert_array_equal(np.array(after["value"], dtype=np.float32), want)
        mu, tau = float(cube["mu"][7]), float(cube["tau_ratio"][12])
        page.mouse.move(*page.evaluate(CELL_POINT_JS, [math.log10(mu), math.log10(tau)]))
        value = float(cube["h2_over_h1"].sel(eps=eps, mu=mu, tau_ratio=tau))
        tip = f"mu:\t{mu:.3g}\ntau_d/tau_f:\t{tau:.3g}\nh2 / h1:\t{value:.3f}"
        page.wait_for_timeout(800)
        tips = [t["text"] for t in deep_query(page, "[class*=tooltip]") if t["visible"]]
        assert tip in tips, tips
        page.screenshot(path=folder / "map_hertz_cells_hover.png")
        assert errors == []
    finally:
        context.close()
