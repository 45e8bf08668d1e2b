"""The image on a real Docker engine: built from the Dockerfile, run as users and platforms run
it (plainly, with a read-only root, as an arbitrary uid), checked over HTTP, a websocket and in
Chromium.

No image registry is reachable here, so the base image is a local stand-in
(tests/docker/make_base.sh: Debian bookworm by debootstrap, with Python 3 and the host's CA
certificates), passed as the Dockerfile's BASE build argument. Without a Docker engine that can
be started the tests skip, saying why, except in CI (CI=true), where they fail.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import time

import pytest
import requests
from appdriver import REPO, free_port, open_page

pytestmark = pytest.mark.docker

BASE = "twoball-base:bookworm"
IMAGE = "twoball:test"
READY_SECONDS = 60


def docker(*arguments: str, check: bool = True, timeout: float = 60) -> str:
    return subprocess.run(
        ["docker", *arguments], capture_output=True, text=True, check=check, timeout=timeout
    ).stdout.strip()


def _engine_answers() -> bool:
    return subprocess.run(["docker", "info"], capture_output=True).returncode == 0


def _no_engine(reason: str):
    if os.environ.get("CI") == "true":
        pytest.fail(f"{reason}, and CI=true: .ci/run installs docker.io and starts dockerd")
    pytest.skip(reason)


@pytest.fixture(scope="module")
def engine():
    """A Docker engine that answers: the running one, or dockerd started here (as root)."""
    if shutil.which("docker") is None:
        _no_engine("no docker client (apt-get install docker.io)")
    if not _engine_answers():
        if shutil.which("dockerd") is None or os.geteuid() != 0:
            _no_engine("no Docker engine answers and dockerd cannot be started here")
        subprocess.Popen(
            ["dockerd"],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
        )
        deadline = time.monotonic() + 60
        while not _engine_answers():
            if time.monotonic() > deadline:
                _no_engine("dockerd did not answer within 60 s")
            time.sleep(1)


@pytest.fixture(scope="module")
def image(engine, artifacts):
    """The image, built on the stand-in base; the build's output goes to test-artifacts/."""
    subprocess.run(["sh", str(REPO / "tests/docker/make_base.sh"), BASE], check=True, timeout=900)
    started = time.monotonic()
    build = subprocess.run(
        ["docker", "build", "--network", "host", "--build-arg", f"BASE={BASE}", "-t", IMAGE, "."],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=1800,
    )
    (artifacts / "docker_build.log").write_text(build.stdout + build.stderr)
    assert build.returncode == 0, build.stderr[-3000:]
    print(f"image built in {time.monotonic() - started:.0f} s")
    return IMAGE


class Container:
    """A running container of the image, published on a free loopback port."""

    def __init__(self, image: str, *options: str):
        self.port = free_port()
        self.base = f"http://127.0.0.1:{self.port}"
        self.started = time.monotonic()
        self.id = docker(
            "run", "--detach", "--publish", f"127.0.0.1:{self.port}:5006",
            "--env", f"ALLOWED_ORIGIN=127.0.0.1:{self.port}", *options, image,
        )  # fmt: skip

    def wait_for_app(self) -> float:
        """Seconds from ``docker run`` until /app answers 200 (fails after READY_SECONDS)."""
        while time.monotonic() - self.started < READY_SECONDS:
            try:
                if requests.get(f"{self.base}/app", timeout=5).status_code == 200:
                    return time.monotonic() - self.started
            except requests.RequestException:
                pass
            time.sleep(0.5)
        pytest.fail(f"/app did not answer within {READY_SECONDS} s:\n{self.logs()[-3000:]}")

    def logs(self) -> str:
        result = subprocess.run(["docker", "logs", self.id], capture_output=True, text=True)
        return result.stdout + result.stderr

    def remove(self) -> None:
        docker("rm", "--force", self.id, check=False)


@pytest.fixture
def run(image, artifacts, request):
    """Start containers of the image; each is removed afterwards, its log saved, and the test
    fails on a traceback in it."""
    started: list[Container] = []

    def start(*options: str) -> Container:
        container = Container(image, *options)
        started.append(container)
        return container

    yield start
    for number, container in enumerate(started):
        log = container.logs()
        (artifacts / f"docker_{request.node.name}_{number}.log").write_text(log)
        container.remove()
        assert "Traceback" not in log, log[-3000:]


def _websocket_status(base: str, origin: str) -> int:
    """The status of a websocket handshake on /app/ws sent with ``origin``, carrying a real
    session token from the page, so that only the origin can make it fail."""
    page = requests.get(f"{base}/app", timeout=30).text
    token = re.search(r'"token":\s*"([^"]+)"', page) or re.search(r"token=([\w.-]+)", page)
    assert token, "no session token in the page"
    handshake = {
        "Upgrade": "websocket",
        "Connection": "Upgrade",
        "Sec-WebSocket-Key": "dGhlIHNhbXBsZSBub25jZQ==",
        "Sec-WebSocket-Version": "13",
        "Sec-WebSocket-Protocol": f"bokeh, {token.group(1)}",
        "Origin": origin,
    }
    with requests.get(f"{base}/app/ws", headers=handshake, timeout=30, stream=True) as reply:
        return reply.status_code


def test_image_serves_as_non_root_turns_healthy_and_stops(run, browser, artifacts):
    container = run()
    ready = container.wait_for_app()
    print(f"/app answered {ready:.1f} s after docker run")
    assert docker("exec", container.id, "id", "-u") != "0"
    deadline = time.monotonic() + 30
    health = ""
    while time.monotonic() < deadline and health != "healthy":
        health = docker("inspect", "--format", "{{.State.Health.Status}}", container.id)
        time.sleep(0.5)
    assert health == "healthy", f"health status {health!r} 30 s after /app answered"
    context, page, errors = open_page(
        browser, f"{container.base}/app?eps=0.9&mu=0.01&tau_ratio=0.01"
    )
    try:
        page.get_by_text("delayed rebound").first.wait_for()
        page.screenshot(path=artifacts / "docker_app.png", full_page=True)
        assert errors == []
    finally:
        context.close()
    # the browser's own origin may open the websocket, any other is refused
    assert _websocket_status(container.base, container.base) == 101
    assert _websocket_status(container.base, "http://elsewhere.example:5006") == 403
    # the server ends on docker stop's SIGTERM (exit 0 or 143), not by the SIGKILL that follows
    # the grace period (137); how long it takes is printed (about 1 s on an idle machine)
    started = time.monotonic()
    docker("stop", "--time", "30", container.id, timeout=60)
    print(f"docker stop took {time.monotonic() - started:.1f} s")
    assert docker("inspect", "--format", "{{.State.ExitCode}}", container.id) in ("0", "143")


@pytest.mark.parametrize(
    "options",
    [
        ("--read-only", "--tmpfs", "/tmp"),
        ("--user", "12345:12345"),
        # a CPU other than the build's finds no usable machine code: as with an empty cache
        ("--env", "NUMBA_CACHE_DIR=/tmp/empty-numba-cache"),
    ],
    ids=["read-only", "arbitrary-uid", "cold-cache"],
)
def test_image_serves_where_platforms_run_it(run, options):
    container = run(*options)
    ready = container.wait_for_app()
    print(f"{' '.join(options)}: /app answered {ready:.1f} s after docker run")
    page = requests.get(f"{container.base}/app", timeout=30)
    assert page.status_code == 200 and "bokeh" in page.text.lower()
