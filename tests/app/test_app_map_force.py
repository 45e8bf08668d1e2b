"""The map's force switch and the Stack scene's "advanced" eps per contact in Chromium: the
switch shows the shipped Hertz cube and says so, the URL follows, a bad entry is reported and
the page goes on. Screenshots go to test-artifacts/map_force/."""

from __future__ import annotations

import re

import pytest
from appdriver import fingerprint, open_page, page_query, wait_for_change
from playwright.sync_api import expect

pytestmark = pytest.mark.browser


def test_the_map_switches_to_the_hertz_cube(browser, app_server, artifacts):
    base, _ = app_server
    folder = artifacts / "map_force"
    folder.mkdir(exist_ok=True)
    context, page, errors = open_page(browser, f"{base}/app?scene=map")
    try:
        expect(page.get_by_text("Slice of the shipped cube").first).to_be_visible(timeout=60_000)
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
        expect(page.get_by_text("Slice of the shipped cube").first).to_be_visible(timeout=60_000)
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
