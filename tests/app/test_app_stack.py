"""The Stack scene (app/stack.py) in Chromium: it shows the library's numbers, its sliders
rerun the stack and write the URL, a bad URL value is reported, and a phone gets no sideways
scroll. Screenshots go to test-artifacts/stack/."""

from __future__ import annotations

import pytest
from appdriver import open_page, page_query, press_slider, slider_titles, sources_with
from playwright.sync_api import expect

from twoball.stacks import simulate_stack
from twoball.units import number_text

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


def test_a_stack_the_solver_refuses_says_why_and_the_app_goes_on(browser, app_server):
    """Six balls, each 0.01 of the one below: each slider within its range, the top ball 1e-10
    of the bottom one, outside the solver's masses. A message, no stale plot, no traceback
    (the server log is checked by the fixture); a valid ratio then draws again."""
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
