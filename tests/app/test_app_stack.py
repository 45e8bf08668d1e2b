"""The Stack scene (app/stack.py) in Chromium: it shows the library's numbers, its sliders
rerun the stack and write the URL, a bad URL value is reported, and a phone gets no sideways
scroll. Screenshots go to test-artifacts/stack/."""

from __future__ import annotations

import pytest
from appdriver import open_page, page_query, press_slider, slider_titles, sources_with
from playwright.sync_api import expect

import twoball
from app.state import ExplorerState
from twoball.stacks import simulate_stack
from twoball.units import DIMENSIONLESS, number_text

pytestmark = pytest.mark.browser


def test_the_stack_scene_shows_the_library_and_follows_its_sliders(browser, app_server, artifacts):
    base, _ = app_server
    folder = artifacts / "stack"
    folder.mkdir(exist_ok=True)
    context, page, errors = open_page(browser, f"{base}/app?scene=stack&N=3&ratio=0.2&gap=0.2")
    try:
        expected = simulate_stack([0.2, 0.2], 0.9, 0.2)
        expect(page.get_by_text("3 balls, linear force")).to_be_visible(timeout=60_000)
        expect(page.get_by_text(f"h1 = {number_text(expected.h1)}").first).to_be_visible()
        page.screenshot(path=folder / "three.png", full_page=True)
        balls = next(i for i, t in enumerate(slider_titles(page)) if t.startswith("balls N"))
        assert press_slider(page, balls) > 0, "the balls slider did not redraw the stack"
        four = simulate_stack([0.2] * 3, 0.9, 0.2)
        expect(page.get_by_text("4 balls, linear force")).to_be_visible()
        expect(page.get_by_text(f"h1 = {number_text(four.h1)}").first).to_be_visible()
        page.wait_for_timeout(600)  # the URL is written shortly after a change
        assert page_query(page)["N"] == "4" and page_query(page)["scene"] == "stack"
        page.screenshot(path=folder / "four.png", full_page=True)
        page.get_by_role("button", name="hertz").click()
        hertz = simulate_stack([0.2] * 3, 0.9, 0.2, force="hertz")
        expect(page.get_by_text("4 balls, hertz force")).to_be_visible(timeout=60_000)
        expect(page.get_by_text(f"h1 = {number_text(hertz.h1)}").first).to_be_visible()
        page.wait_for_timeout(600)
        assert page_query(page)["force"] == "hertz"
        page.screenshot(path=folder / "four_hertz.png", full_page=True)
        assert errors == []
    finally:
        context.close()


def test_a_page_opened_on_the_stack_gets_the_two_ball_sliders_with_the_drop(
    browser, app_server, artifacts
):
    """A page opened on the Stack has only the stack's sliders (the two-ball ones are made when
    a scene they drive is first shown: app/controls.py); its Drop tab brings them, following
    the URL's mu, above the (hidden) stack's, and they drive the drop."""
    base, _ = app_server
    folder = artifacts / "stack"
    folder.mkdir(exist_ok=True)
    context, page, errors = open_page(browser, f"{base}/app?scene=stack&mu=0.1")
    try:
        expect(page.get_by_text("3 balls, linear force")).to_be_visible(timeout=60_000)
        assert not any(t.startswith("mu = m2/m1") for t in slider_titles(page))
        page.locator(".bk-tab", has_text="Drop").click()
        d = ExplorerState()
        drop = twoball.simulate(d.eps, 0.1, d.tau_ratio, height=d.height, until="second")
        summary = page.get_by_text(f"h1 = {DIMENSIONLESS.height(drop.h1)}").first
        expect(summary).to_be_visible(timeout=60_000)
        expect(page.locator(".bk-slider-title", has_text="mu = m2/m1").first).to_be_visible()
        expect(page.locator(".bk-slider-title", has_text="balls N").first).to_be_hidden()
        titles = [t.split(":")[0] for t in slider_titles(page)]  # (a title, then its value)
        assert titles.index("eps (restitution)") < titles.index("balls N")  # (their order)
        assert "mu = m2/m1 (log scale): 0.1" in slider_titles(page)  # (the URL's mu)
        page.screenshot(path=folder / "stack_then_drop.png", full_page=True)
        assert press_slider(page, "eps") > 0, "the eps slider did not redraw the drop"
        page.wait_for_timeout(600)  # the URL is written shortly after a change
        query = page_query(page)
        assert query["scene"] == "drop" and float(query["eps"]) != d.eps
        assert errors == []
    finally:
        context.close()


def test_a_bad_stack_value_in_the_url_is_reported(browser, app_server):
    base, _ = app_server
    context, page, errors = open_page(browser, f"{base}/app?scene=stack&N=9&force=spring")
    try:
        expect(page.get_by_text("URL N: balls must be a whole number from 2 to 8")).to_be_visible(
            timeout=60_000
        )
        expect(page.get_by_text("URL force: must be one of linear, hertz")).to_be_visible()
        expect(page.get_by_text("3 balls, linear force")).to_be_visible()
        assert errors == []
    finally:
        context.close()
    # eps per contact of the wrong length: its message seen without opening "advanced" (a new
    # user found it only inside the folded card)
    url = f"{base}/app?scene=stack&N=3&eps_contacts=0.9,0.8"
    context, page, errors = open_page(browser, url)
    try:
        expect(page.get_by_text("give 3 values for 3 balls").first).to_be_visible(timeout=60_000)
        expect(page.get_by_placeholder("e.g. 0.9, 0.8, 0.7")).to_be_visible()
        assert errors == []
    finally:
        context.close()


# The opacity of each plot's canvas as seen: its own times that of every element around it
# (through Panel's shadow roots).
PLOT_OPACITY_JS = """() => {
  const out = [];
  const walk = (root) => {
    for (const el of root.querySelectorAll("*")) {
      if (el.shadowRoot) walk(el.shadowRoot);
      if (el.tagName !== "CANVAS" || !el.checkVisibility()) continue;
      const box = el.getBoundingClientRect();
      if (box.width < 100 || box.height < 100) continue;
      let opacity = 1;
      for (let node = el; node; node = node.parentNode || node.host) {
        if (node.nodeType === 1) opacity *= parseFloat(getComputedStyle(node).opacity);
      }
      out.push(opacity);
    }
  };
  walk(document);
  return out;
}"""


def test_a_stack_the_solver_refuses_says_why_and_the_app_goes_on(browser, app_server):
    """Opened on six balls, each 0.01 of the one below (each slider within its range, the top
    ball 1e-10 of the bottom one, outside the solver's masses): a message, nothing plotted (no
    stack carried yet), no traceback (the server log is checked by the fixture); a valid ratio
    then draws again."""
    base, _ = app_server
    context, page, errors = open_page(browser, f"{base}/app?scene=stack&N=6&ratio=0.01")
    try:
        expect(page.get_by_text("outside what the solver carries")).to_be_visible(timeout=60_000)
        assert not [s for s in sources_with(page, "t", "h", "text") if s["t"]]  # no apexes
        page.goto(f"{base}/app?scene=stack&N=6&ratio=0.2")
        expect(page.get_by_text("6 balls, linear force")).to_be_visible(timeout=60_000)
        assert errors == []
    finally:
        context.close()


def test_a_slider_into_a_refused_stack_keeps_the_last_one_dimmed(browser, app_server, artifacts):
    """Seven balls, each 0.04 of the one below, then the balls slider to eight: the top ball
    is 1.6e-10 of the bottom one, refused. The plots went empty; now the message says why and
    what the plots show, the last stack carried stays on them, dimmed, the page is not left
    "pending", and a step back draws seven balls again, undimmed."""
    base, _ = app_server
    context, page, errors = open_page(browser, f"{base}/app?scene=stack&N=7&ratio=0.04")
    try:
        expect(page.get_by_text("7 balls, linear force")).to_be_visible(timeout=60_000)
        seven = [s["text"] for s in sources_with(page, "t", "h", "text") if s["t"]]
        assert seven and page.evaluate(PLOT_OPACITY_JS) == [1, 1, 1, 1]
        balls = next(i for i, t in enumerate(slider_titles(page)) if t.startswith("balls N"))
        assert press_slider(page, balls) > 0, "the refusal did not answer the slider's move"
        expect(page.get_by_text("outside what the solver carries")).to_be_visible()
        expect(page.get_by_text("ratio of at least 0.06, or at most 7 balls")).to_be_visible()
        last = "Dimmed below: the last stack it carried, 7 balls with mass ratio 0.04"
        expect(page.get_by_text(last)).to_be_visible()
        assert [s["text"] for s in sources_with(page, "t", "h", "text") if s["t"]] == seven
        page.wait_for_function(f"() => ({PLOT_OPACITY_JS})().every((o) => o < 0.5)")
        assert page.evaluate("document.body.classList.contains('twoball-pending')") is False
        page.wait_for_timeout(600)
        assert page_query(page)["N"] == "8"  # (the URL says what was asked for)
        page.screenshot(path=artifacts / "stack" / "refused-dimmed.png", full_page=True)
        assert press_slider(page, balls, key="ArrowLeft") > 0  # (the same stack as before)
        expect(page.get_by_text("7 balls, linear force")).to_be_visible()
        assert page.evaluate("document.body.classList.contains('twoball-pending')") is False
        expect(page.get_by_text("outside what the solver carries")).to_be_hidden()
        page.wait_for_function(f"() => ({PLOT_OPACITY_JS})().every((o) => o == 1)")
        assert errors == []
    finally:
        context.close()


def test_the_stack_scene_fits_a_phone(browser, app_server, artifacts):
    base, _ = app_server
    context, page, errors = open_page(browser, f"{base}/app?scene=stack", viewport=(390, 844))
    try:
        expect(page.get_by_text("3 balls, linear force")).to_be_visible(timeout=60_000)
        assert page.evaluate("document.documentElement.scrollWidth") <= 390
        # nothing of the scene is cut off at the right (its sliders once made it 600 px wide)
        caption = page.get_by_text("Each ball is").bounding_box()
        assert caption["x"] + caption["width"] <= 390
        page.screenshot(path=artifacts / "stack" / "phone.png", full_page=True)
        assert errors == []
    finally:
        context.close()


# The heights plot's frame (where the data are drawn), its legend, each apex label's box, the
# smallest gap in px between neighbouring x tick labels (negative: they overlap), all as Bokeh
# draws them; and the stage's frame height and the stack of balls drawn on it, in px.
STACK_GEOMETRY_JS = """() => {
  const models = [...Bokeh.documents[0].all_models];
  const shown = (m) => Bokeh.index.find_one(m) != null;
  const plot = models.find((m) => Array.isArray(m.renderers) && Array.isArray(m.center)
    && m.center.some((c) => c.constructor.__name__ === "LabelSet") && shown(m));
  const view = Bokeh.index.find_one(plot);
  const box = (b) => ({left: b.left, top: b.top, right: b.right, bottom: b.bottom,
                       width: b.width, height: b.height});
  const panels = [...plot.above, ...plot.center, ...plot.below, ...plot.left, ...plot.right];
  const legend = panels.find((m) => m.constructor.__name__ === "Legend");
  const {TextBox} = Bokeh.require("core/graphics");
  const labels = [];
  for (const set of panels.filter((m) => m.constructor.__name__ === "LabelSet")) {
    const lv = Bokeh.index.find_one(set);
    for (let i = 0; i < lv.text.length; i++) {
      const text = lv.text.get(i);
      if (text == null) continue;
      const graphics = new TextBox({text: `${text}`});
      graphics.position = {sx: lv.sx[i] + lv.x_offset.get(i), sy: lv.sy[i] - lv.y_offset.get(i)};
      graphics.visuals = lv.visuals.text.values(i);
      const {p0, p1, p2, p3} = graphics.rect();
      const xs = [p0.x, p1.x, p2.x, p3.x], ys = [p0.y, p1.y, p2.y, p3.y];
      labels.push({text, left: Math.min(...xs), right: Math.max(...xs),
                   top: Math.min(...ys), bottom: Math.max(...ys)});
    }
  }
  const time = plot.below.find((m) => m.constructor.__name__ === "LinearAxis");
  const axis = Bokeh.index.find_one(time);
  const coords = axis.tick_coords.major;
  const ticks = axis.compute_labels(coords[0]);
  ticks.visuals = axis.visuals.major_label_text.values();
  ticks.base_font_size = axis.plot_view.base_font_size;
  const widths = ticks.items.map((label) => label.size().width);
  const at = axis.scoords(coords)[0];
  let gap = Infinity;
  for (let i = 1; i < at.length; i++) {
    gap = Math.min(gap, Math.abs(at[i] - at[i - 1]) - (widths[i] + widths[i - 1]) / 2);
  }
  const whole = view.el.getBoundingClientRect();
  const balls = models.find((m) => m.constructor.__name__ === "GlyphRenderer" && shown(m)
    && m.glyph.constructor.__name__ === "Circle");
  const bv = Bokeh.index.find_one(balls);
  const data = balls.data_source.data instanceof Map ? Object.fromEntries(balls.data_source.data)
    : balls.data_source.data;
  const y = Array.from(data.y), r = Array.from(data.r);
  const scale = bv.coordinates.y_scale;
  const tops = y.map((v, i) => scale.compute(v + r[i]));
  const feet = y.map((v, i) => scale.compute(v - r[i]));
  const radii = y.map((v, i) => Math.abs(tops[i] - scale.compute(v)));
  return {frame: box(view.frame.bbox), figure: {width: whole.width, height: whole.height},
          legend: box(Bokeh.index.find_one(legend).bbox), labels, ticks: at.length, gap,
          stage: bv.plot_view.frame.bbox.height, stack: Math.max(...feet) - Math.min(...tops),
          smallest: Math.min(...radii)};
}"""


def stack_geometry(page) -> dict:
    return page.evaluate(STACK_GEOMETRY_JS)


def labels_inside(geometry: dict) -> bool:
    """Each apex label lies within the plot's frame: not over an axis' labels, not cut off."""
    frame = geometry["frame"]
    return all(
        frame["left"] <= label["left"] and label["right"] <= frame["right"]
        and frame["top"] <= label["top"] and label["bottom"] <= frame["bottom"]
        for label in geometry["labels"]
    )  # fmt: skip


def readable_stack(geometry: dict) -> bool:
    """The balls at rest stand at least 80 px and a third of the stage tall, the top one at
    least 2 px in radius (an eight-ball stack was 40 px tall, its top ball under a pixel)."""
    stack, stage = geometry["stack"], geometry["stage"]
    return stack >= max(80, stage / 3) and geometry["smallest"] >= 2


@pytest.mark.parametrize("size", [(1280, 720), (1920, 1080)], ids=["1280x720", "1920x1080"])
def test_eight_balls_fit_a_projector(browser, app_server, artifacts, size):
    """Presentation mode, eight balls: the apex labels stay inside the plot (h1's ran into the
    height axis' labels), the legend stands compact above the curves (beside them it took a
    third of the plot's width), and the stack of balls is drawn at a readable height."""
    base, _ = app_server
    url = f"{base}/app?present=1&scene=stack&N=8"
    context, page, errors = open_page(browser, url, viewport=size)
    try:
        expect(page.get_by_text("8 balls, linear force")).to_be_visible(timeout=60_000)
        page.wait_for_timeout(800)
        geometry = stack_geometry(page)
        frame, legend = geometry["frame"], geometry["legend"]
        page.screenshot(path=artifacts / "stack" / f"projector-eight-{size[0]}.png")
        assert len(geometry["labels"]) == 2 and labels_inside(geometry), geometry
        assert legend["bottom"] <= frame["top"], geometry  # above the curves, not beside them
        assert frame["width"] >= 0.7 * geometry["figure"]["width"], geometry
        assert frame["height"] >= 150, geometry
        assert geometry["gap"] >= 12, geometry
        assert readable_stack(geometry), geometry
        assert errors == []
    finally:
        context.close()


def test_eight_balls_fit_a_phone(browser, app_server, artifacts):
    """On a phone, eight balls: the time axis' tick labels keep 12 px apart (they ran into each
    other, 0 to 14000 every 2000), h1's label is not cut at the plot's left, and the stack of
    balls is drawn at a readable height."""
    base, _ = app_server
    url = f"{base}/app?scene=stack&N=8"
    context, page, errors = open_page(browser, url, viewport=(390, 844))
    try:
        expect(page.get_by_text("8 balls, linear force")).to_be_visible(timeout=60_000)
        page.wait_for_timeout(800)
        geometry = stack_geometry(page)
        page.screenshot(path=artifacts / "stack" / "phone-eight.png", full_page=True)
        assert len(geometry["labels"]) == 2 and labels_inside(geometry), geometry
        assert geometry["ticks"] >= 3 and geometry["gap"] >= 12, geometry
        assert readable_stack(geometry), geometry
        assert page.evaluate("document.documentElement.scrollWidth") <= 390
        assert errors == []
    finally:
        context.close()
