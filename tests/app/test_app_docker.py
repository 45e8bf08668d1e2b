"""The Docker image without a Docker engine: the Dockerfile's install and start commands (the
scripts app/install.sh and app/start.sh, which its RUN and CMD call) run here in a fresh virtual
environment, on a copy of the build context (the repository minus .dockerignore), and the
served page is checked the way the HEALTHCHECK and a browser see it."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest
import requests
from apphelpers import REPO, free_port, open_page, serve, wait_until_served

pytestmark = pytest.mark.docker

DOCKERFILE = (REPO / "Dockerfile").read_text()


def instructions(name: str) -> list[str]:
    """The arguments of every ``name`` instruction of the Dockerfile (continuations joined)."""
    text = re.sub(r"\\\n\s*", " ", DOCKERFILE)
    return [m.group(1).strip() for m in re.finditer(rf"^{name}\s+(.*)$", text, re.MULTILINE)]


def test_dockerfile_is_slim_non_root_and_calls_the_tested_scripts():
    assert re.fullmatch(r"python:3\.\d+-slim", instructions("FROM")[0])
    user = instructions("USER")
    assert user and user[-1] not in ("root", "0")
    assert DOCKERFILE.index("\nUSER ") < DOCKERFILE.index("RUN sh app/install.sh")
    assert instructions("RUN")[-1] == "sh app/install.sh /home/twoball/venv"
    assert instructions("CMD") == ['["sh", "app/start.sh", "/home/twoball/venv"]']
    assert "5006" in instructions("EXPOSE")[0]
    assert any("ALLOWED_ORIGIN=" in env for env in instructions("ENV"))
    assert "/liveness" in instructions("HEALTHCHECK")[0]
    assert '--allow-websocket-origin "${ALLOWED_ORIGIN' in (REPO / "app/start.sh").read_text()
    assert "--address 0.0.0.0" in (REPO / "app/start.sh").read_text()


def image_environment() -> dict[str, str]:
    """This environment without what the image does not have (an active venv, a numba cache
    directory elsewhere)."""
    return {k: v for k, v in os.environ.items() if k not in ("VIRTUAL_ENV", "NUMBA_CACHE_DIR")}


def build_context(target: Path) -> Path:
    """Copy the repository as ``docker build`` would send it (.dockerignore applied)."""
    patterns = [
        line.strip().split("/")[-1]
        for line in (REPO / ".dockerignore").read_text().splitlines()
        if line.strip() and not line.startswith("#")
    ]
    shutil.copytree(REPO, target, ignore=shutil.ignore_patterns(*patterns))
    return target


@pytest.fixture(scope="module")
def image(tmp_path_factory):
    """The image's file system: build context plus what app/install.sh makes of it."""
    root = tmp_path_factory.mktemp("image")
    context = build_context(root / "twoball")
    venv = root / "venv"
    env = image_environment()
    subprocess.run(
        ["sh", "app/install.sh", str(venv)], cwd=context, env=env, check=True, timeout=1200
    )
    return context, venv


def test_the_install_ships_the_cubes_and_builds_the_numba_cache(image):
    context, venv = image
    assert (context / "precomputed" / "map.zarr" / "zarr.json").is_file()
    assert not (context / ".venv").exists() and not (context / ".git").exists()
    assert list((context / "twoball" / "__pycache__").glob("*.nbi")), "no numba cache was built"
    # the installed package opens the shipped cube (editable install: precomputed/ beside it)
    out = subprocess.run(
        env=image_environment(),
        args=[
            str(venv / "bin" / "python"),
            "-c",
            "import twoball; print(twoball.load_cube('map').sizes['eps'])",
        ],
        cwd="/",
        capture_output=True,
        text=True,
        check=True,
    )
    assert int(out.stdout) > 1


def test_the_started_image_serves_the_app(image, browser, artifacts):
    context, venv = image
    port = free_port()
    env = {**image_environment(), "PORT": str(port), "ALLOWED_ORIGIN": f"127.0.0.1:{port}"}
    log = artifacts / "docker_start.log"
    process = serve(["sh", "app/start.sh", str(venv)], log, cwd=context, env=env)
    base = f"http://127.0.0.1:{port}"
    try:
        wait_until_served(f"{base}/liveness", process)  # what the HEALTHCHECK asks
        page_html = requests.get(f"{base}/app", timeout=30)
        assert page_html.status_code == 200 and "bokeh" in page_html.text.lower()
        ctx, page, errors = open_page(browser, f"{base}/app?eps=0.9&mu=0.01&tau_ratio=0.01")
        try:
            page.get_by_text("delayed rebound").first.wait_for()
            page.screenshot(path=artifacts / "docker_app.png", full_page=True)
            assert errors == []
        finally:
            ctx.close()
        # a browser from an origin that is not allowed cannot open the websocket
        handshake = {
            "Upgrade": "websocket",
            "Connection": "Upgrade",
            "Sec-WebSocket-Key": "dGhlIHNhbXBsZSBub25jZQ==",
            "Sec-WebSocket-Version": "13",
        }
        refused = requests.get(
            f"{base}/app/ws",
            headers={**handshake, "Origin": "http://elsewhere.example:5006"},
            timeout=30,
        )
        assert refused.status_code == 403
    finally:
        process.terminate()
        process.wait(timeout=30)
    assert "Traceback" not in log.read_text()
