"""Fixtures of the app's tests: the repository on sys.path (the app is ``app/``), a served app
on a free loopback port, and Debian's Chromium driven by Playwright.

Without /usr/bin/chromium the browser tests skip, saying so, except when CI=true: then they
fail. Screenshots go to test-artifacts/ (gitignored).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest
from appdriver import (
    ARTIFACTS,
    CHROMIUM,
    CHROMIUM_ARGS,
    REPO,
    free_port,
    panel_serve,
    serve,
    server_errors,
    wait_until_served,
)

if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))


@pytest.fixture(scope="session")
def artifacts() -> Path:
    ARTIFACTS.mkdir(exist_ok=True)
    return ARTIFACTS


@pytest.fixture(scope="session")
def app_server(artifacts):
    """``panel serve app`` from the repository root; yields (base url, server log path)."""
    port = free_port()
    log = artifacts / "app_server.log"
    process = serve(
        panel_serve("app", port),
        log,
    )
    base = f"http://127.0.0.1:{port}"
    try:
        wait_until_served(f"{base}/app", process)
        yield base, log
    finally:
        process.terminate()
        process.wait(timeout=30)


@pytest.fixture(scope="session")
def browser():
    if not CHROMIUM.exists():
        if os.environ.get("CI") == "true":
            pytest.fail(f"{CHROMIUM} is missing and CI=true: install Debian's chromium")
        pytest.skip(f"{CHROMIUM} is missing (apt-get install chromium); browser tests skipped")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
        yield chromium
        chromium.close()


@pytest.fixture(autouse=True)
def server_log_stays_clean(request):
    """Every test that uses the served app fails on an error or traceback in its log."""
    yield
    if "app_server" in request.fixturenames:
        _, log = request.getfixturevalue("app_server")
        errors = server_errors(log)
        assert errors == [], "the server logged:\n" + "\n".join(errors)
