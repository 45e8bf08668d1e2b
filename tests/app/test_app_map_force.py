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
from test_app_map import code_values, three_digits

from app.map_browser import DECODE_JS, VALUE_JS
from app.map_slices import cube_colour_limits, eps_slice, nearest_eps, slice_image

pytestmark = pytest.mark.browser
# the map's image as drawn (its values decoded from the codes sent, flattened) and its colour
# mapper's range, in the browser
IMAGE_JS = """() => {
  const models = [...Bokeh.documents[0].all_models];
  const view = [...Bokeh.index.all_views()].find((v) => v.model.glyph
    && v.model.glyph.constructor.__name__ === "Image");
  const data = view.glyph.image.get(0);
  const mapper = models.find((m) => m.constructor.__name__.endsWith("ColorMapper"));
  return [Array.from(data, (v) => (Number.isNaN(v) ? null : v)), [mapper.low, mapper.high],
          mapper.palette, models.filter((m) => m.constructor.__name__ === "ColorBar").length];
}"""
# the Hertz map's cells as drawn: their edges, placed in the browser (log10)
CELL_EDGES_JS = """() => {
  const view = [...Bokeh.index.all_views()].find((v) => v.model.glyph
    && v.model.glyph.constructor.__name__ === "Quad");
  const {left, right, bottom, top} = view.glyph;
  return [left, right, bottom, top].map((edges) => Array.from(edges));
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
        limits = cube_colour_limits("map", "h2_over_h1")  # (every slice's)
        _, (low, high) = slice_image(eps_slice(eps, "h2_over_h1"), "h2_over_h1", limits)
        drawn, mapped, _, _ = page.evaluate(IMAGE_JS)
        drawn = np.array([np.nan if v is None else v for v in drawn])
        cube = eps_slice(eps, "h2_over_h1")["h2_over_h1"].transpose("tau_ratio", "mu").values
        want = np.where(cube > 0, cube, np.nan).ravel()  # (grey: none)
        np.testing.assert_array_equal(drawn, three_digits(want))  # (what the hover shows)
        assert mapped == pytest.approx([low, high])
        (outline,) = sources_with(page, "xs", "ys")
        assert len(outline["xs"]) == 1
        page.screenshot(path=folder / "map_eps_moved.png", full_page=True)
        assert errors == []
    finally:
        context.close()


# every uint16 code's value and hover text, as the map's own JavaScript gives them
ALL_CODES_JS = """([decode, text]) => {
  const value = new Function("code", decode + "return decode(code);");
  const shown = new Function("value", text);
  const codes = Array.from({length: 65536}, (_, code) => code);
  return [codes.map((code) => (Number.isNaN(value(code)) ? null : value(code))),
          codes.map(shown)];
}"""


def test_the_browser_reads_every_code_as_python_does(browser):
    """For every uint16 code the browser's value is the one Python reads from the code's
    digits (tests/app/test_app_map.py ``code_values``), and the hover's text is Python's
    ``f"{value:.3g}"`` of it, "none: ..." for no value."""
    page = browser.new_page()
    try:
        values, texts = page.evaluate(ALL_CODES_JS, [DECODE_JS, VALUE_JS])
    finally:
        page.close()
    want = code_values(np.arange(65536, dtype=np.uint16))
    np.testing.assert_array_equal(np.array(values, dtype=float), want)  # (None: NaN)
    shown = [f"{v:.3g}" if v == v else "none: an apex below 0, or missing" for v in want]
    assert texts == shown
    assert {"1.97", "0.0123", "23.8", "1.48e-05", "-0.00708", "0"} <= set(texts)


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


def tooltips(page) -> list[str]:
    """The visible tooltips' text."""
    page.wait_for_timeout(800)
    return [t["text"] for t in deep_query(page, "[class*=tooltip]") if t["visible"]]


def test_the_hertz_map_s_cells_take_an_eps_move_and_hover(browser, app_server, artifacts):
    """The Hertz map's rectangles (one a cell, app/map_slices.py ``drawn_as_cells``), placed in
    the browser from their index: each lies between its axis values' log10 midpoints; an eps
    move gives them the new slice's codes; the hover over a cell gives its mu, tau_d/tau_f and
    its value, read here from the cube: exactly its three significant digits (``.3g``)."""
    import math

    import twoball

    base, _ = app_server
    folder = artifacts / "map_force"
    folder.mkdir(exist_ok=True)
    context, page, errors = open_page(browser, f"{base}/app?scene=map&map_force=hertz&eps=0.6")
    cube = twoball.load_cube("hertz-h1e4")
    try:
        expect(page.get_by_text("Hertz length unit").first).to_be_visible(timeout=60_000)
        left, right, bottom, top = (np.array(e) for e in page.evaluate(CELL_EDGES_JS))
        cells = np.arange(2500)
        for low, high, axis, index in ((left, right, "mu", cells % 50),
                                       (bottom, top, "tau_ratio", cells // 50)):  # fmt: skip
            logs = np.log10(cube[axis].values)
            edges = np.r_[logs[0], (logs[1:] + logs[:-1]) / 2, logs[-1]]
            np.testing.assert_allclose(low, edges[index], atol=1e-6)
            np.testing.assert_allclose(high, edges[index + 1], atol=1e-6)
        (before,) = sources_with(page, "value")
        assert press_slider(page, "eps", key="End") > 0
        eps = nearest_eps(float(page.locator(".bk-slider-value").first.inner_text()), "hertz-h1e4")
        expect(page.get_by_text(f"at eps = {eps:g} (nearest").first).to_be_visible()
        page.wait_for_timeout(500)
        (after,) = sources_with(page, "value")
        assert after["value"] != before["value"]
        assert np.array_equal(page.evaluate(CELL_EDGES_JS)[0], left)  # (still in place)
        mu, tau = float(cube["mu"][7]), float(cube["tau_ratio"][12])
        page.mouse.move(*page.evaluate(CELL_POINT_JS, [math.log10(mu), math.log10(tau)]))
        value = float(cube["h2_over_h1"].sel(eps=eps, mu=mu, tau_ratio=tau))
        tips = {t for t in tooltips(page) if t.startswith("mu:\t")}
        (tip,) = tips  # (the tooltip, and the element holding it)
        head = f"mu:\t{mu:#.3g}\ntau_d/tau_f:\t{tau:#.3g}\nh2 / h1:\t"  # (JS toPrecision)
        assert tip == f"{head}{value:.3g}", tip
        page.screenshot(path=folder / "map_hertz_cells_hover.png")
        assert errors == []
    finally:
        context.close()


# where a point of the linear map (log10 mu, log10 tau_ratio) lies in the page, in px
IMAGE_POINT_JS = CELL_POINT_JS.replace('"Quad"', '"Image"')


def test_the_map_s_hover_reads_a_value_and_says_none(browser, app_server, artifacts):
    """The linear map's hover reads a cell's value from its code: the cube's value to three
    significant digits, exactly as Python's ``.3g`` prints it (small ones too), and, over a
    grey cell (an apex below 0), says there is none: Bokeh had printed "NaN" before the
    hover's own text could say so."""
    import math

    from app.map_slices import map_cube

    base, _ = app_server
    folder = artifacts / "map_force"
    folder.mkdir(exist_ok=True)
    context, page, errors = open_page(browser, f"{base}/app?scene=map&eps=0.9")
    cube = map_cube()["h2_over_h1"].sel(eps=0.9)
    try:
        expect(page.get_by_text("at eps = 0.9 (nearest").first).to_be_visible(timeout=60_000)
        values = cube.transpose("tau_ratio", "mu").values
        (rows, columns) = np.nonzero(values <= 0)
        small = np.unravel_index(np.nanargmin(np.where(values > 0, values, np.nan)), values.shape)
        cells = ((40, 30, False), (10, 60, False), (*small, False), (rows[0], columns[0], True))
        for row, column, none in cells:
            mu, tau = float(cube["mu"][column]), float(cube["tau_ratio"][row])
            page.mouse.move(0, 0)
            page.mouse.move(*page.evaluate(IMAGE_POINT_JS, [math.log10(mu), math.log10(tau)]))
            tips = {t for t in tooltips(page) if t.startswith("mu:\t")}
            (tip,) = tips  # (the tooltip, and the element holding it)
            head = f"mu:\t{mu:#.3g}\ntau_d/tau_f:\t{tau:#.3g}\nh2 / h1:\t"  # (JS toPrecision)
            assert tip.startswith(head), tip
            shown = tip[len(head) :]
            if none:
                assert shown == "none: an apex below 0, or missing", tip
                page.screenshot(path=folder / "map_hover_none.png")
            else:
                assert shown == f"{float(values[row, column]):.3g}", tip
        assert errors == []
    finally:
        context.close()
