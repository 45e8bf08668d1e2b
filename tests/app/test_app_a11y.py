"""Accessibility in Chromium: axe-core finds no serious or critical violation on any scene (on a
desktop and on a projector, with a lesson's cover and with a message shown); sliders are named
and read their values as shown; the keyboard reaches every control with a visible focus ring.
The names and the ring come from app/static/a11y.js."""

from __future__ import annotations

import pytest
from appdriver import open_page
from axe_playwright_python.sync_playwright import Axe
from playwright.sync_api import expect

from app.scenes import SCENE_REGISTRY, SCENES

pytestmark = pytest.mark.browser
SERIOUS = ("serious", "critical")

HANDLES_JS = """() => {
  const found = [];
  const walk = (root) => {
    for (const el of root.querySelectorAll("*")) {
      if (el.classList && el.classList.contains("noUi-handle") && el.checkVisibility()) {
        found.push({label: el.getAttribute("aria-label"), text: el.getAttribute("aria-valuetext"),
                    shown: el.getRootNode().querySelector(".bk-slider-value").textContent});
      }
      if (el.shadowRoot) walk(el.shadowRoot);
    }
  };
  walk(document);
  return found;
}"""

FOCUSED_JS = """() => {
  let el = document.activeElement;
  while (el && el.shadowRoot && el.shadowRoot.activeElement) el = el.shadowRoot.activeElement;
  const style = getComputedStyle(el);
  return {tag: el.tagName, cls: String(el.className), outline: style.outlineStyle,
          width: parseFloat(style.outlineWidth), color: style.outlineColor};
}"""


def _serious(page) -> list[str]:
    page.wait_for_timeout(1500)  # a11y.js looks the page over every second
    violations = Axe().run(page).response["violations"]
    return [
        f"{v['id']} ({v['impact']}): {v['nodes'][0]['html'][:120]}"
        for v in violations
        if v["impact"] in SERIOUS
    ]


@pytest.mark.parametrize("present", ["", "&present=1"], ids=["desktop", "projector"])
@pytest.mark.parametrize("scene", list(SCENE_REGISTRY))
def test_axe_finds_no_serious_violation(browser, app_server, scene, present):
    base, _ = app_server
    context, page, errors = open_page(
        browser, f"{base}/app?scene={scene}{present}", viewport=(1366, 768)
    )
    try:
        if scene == "accuracy":
            page.get_by_text("Computing:").wait_for(state="hidden", timeout=120_000)
        assert _serious(page) == []
        assert errors == []
    finally:
        context.close()


@pytest.mark.parametrize("query", ["step=3", "eps=7"], ids=["lesson-cover", "message"])
def test_axe_finds_no_serious_violation_in_a_lesson_or_a_message(browser, app_server, query):
    base, _ = app_server
    context, page, errors = open_page(browser, f"{base}/app?{query}", viewport=(1366, 768))
    try:
        assert _serious(page) == []
        assert errors == []
    finally:
        context.close()


def test_sliders_are_named_and_read_their_values_as_shown(browser, app_server):
    """A log slider's handle holds the exponent (-2); it reads 0.01, as its title shows, and
    follows a move made with the keyboard."""
    base, _ = app_server
    context, page, errors = open_page(browser, f"{base}/app", viewport=(1366, 768))
    try:
        page.wait_for_timeout(1500)
        handles = page.evaluate(HANDLES_JS)
        mu = next(h for h in handles if h["label"] == "mu = m2/m1 (log scale)")
        assert mu["text"] == mu["shown"] == "0.01"
        assert {h["label"] for h in handles} >= {
            "eps (restitution)",
            "mu = m2/m1 (log scale)",
            "tau_d/tau_f (log scale)",
        }
        page.get_by_role("slider", name="mu = m2/m1 (log scale)").press("ArrowRight")
        page.wait_for_function(
            "(js) => eval(js)().some((h) => h.label.startsWith('mu') && h.text !== '0.01')",
            arg=HANDLES_JS,
        )
        mu = next(h for h in page.evaluate(HANDLES_JS) if h["label"].startswith("mu"))
        assert mu["text"] == mu["shown"] and float(mu["text"]) > 0.01
        assert errors == []
    finally:
        context.close()


def test_the_keyboard_reaches_the_controls_with_a_visible_focus(browser, app_server):
    """Tab from the top of the page reaches the preset, the units, the three sliders, the
    scene's buttons and its tabs, each drawn with a 3 px orange ring when focused."""
    base, _ = app_server
    context, page, errors = open_page(browser, f"{base}/app", viewport=(1366, 768))
    try:
        page.wait_for_timeout(1500)
        reached = []
        for _ in range(40):
            page.keyboard.press("Tab")
            focused = page.evaluate(FOCUSED_JS)
            reached.append(focused)
        reached = [f for f in reached if f["tag"] != "BODY"]  # (past the last, back to the top)
        for focused in reached:
            assert focused["outline"] == "solid" and focused["width"] >= 3, focused
            assert focused["color"] == "rgb(230, 159, 0)", focused
        kinds = {f["tag"] for f in reached} | {c for f in reached for c in f["cls"].split()}
        assert {"SELECT", "BUTTON", "noUi-handle", "play", "bk-tab"} <= kinds, kinds
        assert errors == []
    finally:
        context.close()


def _unnamed_focusable(page) -> list[str]:
    """Each element the keyboard can focus whose accessible name (Chromium's, from its
    accessibility tree) is empty: no aria-label, no label, no text of its own."""
    cdp = page.context.new_cdp_session(page)
    found = []
    for node in cdp.send("Accessibility.getFullAXTree")["nodes"]:
        props = {p["name"]: p["value"].get("value") for p in node.get("properties", [])}
        role = (node.get("role") or {}).get("value", "")
        if node.get("ignored") or not props.get("focusable") or role == "RootWebArea":
            continue
        name = (node.get("name") or {}).get("value", "").strip()
        described = cdp.send("DOM.describeNode", {"backendNodeId": node["backendDOMNodeId"]})
        html = described["node"]
        if not name:  # (a generic element, a tab, is read by its text: named by it)
            text = cdp.send("DOM.resolveNode", {"backendNodeId": node["backendDOMNodeId"]})[
                "object"
            ]
            own = cdp.send(
                "Runtime.callFunctionOn",
                {
                    "objectId": text["objectId"],
                    "functionDeclaration": "function () { return this.textContent.trim(); }",
                    "returnByValue": True,
                },
            )["result"]["value"]
            if role == "generic" and own and own != "\u22ef":
                continue
            found.append(f"{role} <{html.get('localName')} {html.get('attributes')}> {own!r}")
    return found


@pytest.mark.parametrize("scene", ["drop", "closeup", "map"])
def test_every_focusable_control_has_a_name(browser, app_server, scene):
    """Chromium's accessibility tree names everything the keyboard reaches (each plot's
    event layer and a toolbar's '⋯' had no name), the advanced inputs opened."""
    base, _ = app_server
    context, page, errors = open_page(browser, f"{base}/app?scene={scene}", viewport=(1366, 768))
    try:
        page.get_by_role("button", name="advanced", exact=True).click()
        page.wait_for_timeout(1500)  # (a11y.js looks the page over every second)
        assert _unnamed_focusable(page) == []
        assert errors == []
    finally:
        context.close()


def test_the_scenes_tabs_are_a_tab_list_with_the_scene_on_screen_selected(browser, app_server):
    """A screen reader hears the scenes as tabs, the one on screen selected (Bokeh draws them
    as plain focusable divs: a new user's tool found no tab), and the selection follows a
    change of scene."""
    base, _ = app_server
    context, page, errors = open_page(browser, f"{base}/app?scene=map")
    try:
        tabs = page.get_by_role("tablist").get_by_role("tab")
        expect(tabs).to_have_count(len(SCENE_REGISTRY))
        titles = [entry.title for entry in SCENE_REGISTRY.values()]
        expect(page.get_by_role("tab", selected=True)).to_have_text(titles[SCENES.index("map")])
        page.get_by_role("tab", name=titles[0]).click()
        expect(page.get_by_role("tab", selected=True)).to_have_text(titles[0])
        assert errors == []
    finally:
        context.close()
