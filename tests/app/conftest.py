"""Fixtures of the app's tests: the repository on sys.path (the app is ``app/``), a served app
on a free loopback port, and Debian's Chromium driven by Playwright.

Without /usr/bin/chromium the browser tests skip, saying so, except when CI=true: then they
fail. Screenshots go to test-artifacts/ (gitignored).
"""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
import requests

REPO = Path(__file__).resolve().parents[2]
ARTIFACTS = REPO / "test-artifacts"
CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def wait_until_served(url: str, process: subprocess.Popen, timeout: float = 180.0) -> None:
    """Poll ``url`` until it answers 200; fail if the server exits or the time runs out."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if process.poll() is not None:
            raise RuntimeError(f"the server exited with status {process.returncode}")
        try:
            if requests.get(url, timeout=5).status_code == 200:
                return
        except requests.RequestException:
            pass
        time.sleep(0.5)
    raise RuntimeError(f"{url} did not answer within {timeout:.0f} s")


def serve(command: list[str], log: Path, cwd: Path = REPO, env: dict | None = None):
    """Start ``command`` (a ``panel serve``), its output in ``log``; returns the process."""
    handle = open(log, "w")  # noqa: SIM115 (closed with the process)
    return subprocess.Popen(
        command, cwd=cwd, stdout=handle, stderr=subprocess.STDOUT, env=env, start_new_session=True
    )


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
        [
            str(Path(sys.executable).parent / "panel"),
            "serve",
            "app",
            "--address",
            "127.0.0.1",
            "--port",
            str(port),
            "--allow-websocket-origin",
            f"127.0.0.1:{port}",
        ],
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
