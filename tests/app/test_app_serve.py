"""``twoball serve`` as a teacher runs it for a class: every core, pages that cost only their
scene, sessions kept apart and given back when closed, and a page that says when the server is
behind. Measured with protocol clients (tools/bokehclient.py: what a browser sends and
receives, without rendering) and, where the page itself is the point, in Chromium.

Speeds are the benchmark's (benchmarks/app_load.py, docs/performance.md); these tests assert what
must hold whatever the machine.
"""

from __future__ import annotations

import asyncio
import os
import signal
import socket
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from urllib.parse import parse_qs, urlparse

import pytest
from appdriver import (
    REPO,
    fingerprint,
    free_port,
    open_page,
    press_slider,
    rss_mb,
    serve,
    server_errors,
    wait_for_change,
    wait_until_served,
)
from bokehclient import PageClient

import twoball
from app.scenes import SCENES
from twoball.units import number_text

TWOBALL = Path(sys.executable).parent / "twoball"
FIRST_DOCUMENT_BYTES = 50_000  # what a page's first document may cost on the network
SCENE_ONLY_SLIDERS = {"stack": "balls N"}  # a widget that only the Stack scene builds


def twoball_serve(port: int, processes: int, executable: Path = TWOBALL) -> list[str]:
    """The command, on loopback; closed sessions are discarded within 6 s (a session counts as
    unused from its websocket's opening to its first pull: a shorter lifetime discarded live
    sessions of a loaded server)."""
    return [
        str(executable), "serve", "--address", "127.0.0.1", "--port", str(port),
        "--allow-websocket-origin", f"127.0.0.1:{port}", "--num-procs", str(processes),
        "--check-unused-sessions", "1000", "--unused-session-lifetime", "5000",
    ]  # fmt: skip


class Served:
    """A running ``twoball serve``: its base URL, log and process."""

    def __init__(self, command: list[str], port: int, log: Path, cwd: Path):
        self.base = f"http://127.0.0.1:{port}"
        self.log = log
        self.process = serve(command, log, cwd=cwd)
        wait_until_served(f"{self.base}/liveness", self.process, timeout=300)

    def stop(self) -> None:
        self.process.terminate()
        self.process.wait(timeout=30)
        errors = server_errors(self.log)
        assert errors == [], "the server logged:\n" + "\n".join(errors)


@pytest.fixture(scope="module")
def two_processes(artifacts, tmp_path_factory):
    """``twoball serve --num-procs 2``, started from a directory that is not the repository."""
    port = free_port()
    served = Served(
        twoball_serve(port, 2), port, artifacts / "serve_server.log", tmp_path_factory.mktemp("x")
    )
    yield served
    served.stop()


def run(coroutine):
    """``asyncio.run`` in a thread of its own: once a browser test has run, Playwright's sync API
    keeps an event loop running in the main thread, where asyncio.run refuses to start."""
    with ThreadPoolExecutor(1) as pool:
        return pool.submit(asyncio.run, coroutine).result()


async def opened(url: str) -> PageClient:
    client = PageClient(url)
    await client.open()
    return client


def slider_titles(client: PageClient) -> set[str]:
    return {m["attributes"].get("title") for m in client.models.values() if m["name"] == "Slider"}


@pytest.mark.parametrize("scene", ["drop", "closeup", "map", "stack"])
def test_a_page_costs_only_the_scene_on_screen(two_processes, scene):
    """Opening a page builds the controls and the scene in its URL, not the other four (a page
    had 514 models and 116 kB), and its first document crosses the network in under 50 kB."""

    async def check() -> None:
        client = await opened(f"{two_processes.base}/app?scene={scene}")
        try:
            assert client.document_wire_bytes <= FIRST_DOCUMENT_BYTES, client.document_wire_bytes
            assert client.document_wire_bytes < client.document_bytes  # deflated on the way
            assert len(client.models) < 250
            titles = slider_titles(client)
            # the two-ball sliders, made when a scene they drive is shown (not the Stack)
            two_ball = {"eps (restitution)", "mu = m2/m1 (log scale)"} <= titles
            assert two_ball == (scene != "stack"), titles
            for owner, title in SCENE_ONLY_SLIDERS.items():
                assert (title in titles) == (owner == scene)
        finally:
            await client.close()

    run(check())


@pytest.mark.parametrize("query", ["scene=drop", "scene=stack", "scene=drop&present=1"])
def test_a_page_s_style_sheets_are_not_sent_again_after_it_has_loaded(two_processes, query):
    """A page's text panes have their style sheets in its first document: once the page has
    loaded, no message changes any model's style sheets. Each summary's first update (Panel's
    whole pane, app.scene.Text) sent them again, 1.4 kB, and the server recomputed the
    document's models for it; what the page still gets then is its text, its player's end and
    its URL."""

    async def check() -> None:
        for _ in range(2):  # (a process's first page of a kind, then one from its kept session)
            client = await opened(f"{two_processes.base}/app?{query}")
            try:
                await asyncio.sleep(1.5)  # (the page's onload callbacks, its URL's rewrite)
                changed = [
                    (event["model"]["id"], event["attr"])
                    for patch in client.patches
                    for event in patch.events
                    if event.get("kind") == "ModelChanged"
                ]
                assert changed, "no patch after the page loaded (its URL is rewritten)"
                assert [c for c in changed if c[1] == "stylesheets"] == [], changed
            finally:
                await client.close()

    run(check())


async def _answer(client: PageClient, sent: float, timeout: float = 30.0) -> list:
    """The patches that answered a move sent at ``sent`` (not the URL's rewrite 0.3 s later, nor
    the header's busy spinner), once the summary's new text has come."""
    summary = next(
        i for i, m in client.models.items() if "h1 = " in str(m["attributes"].get("text", ""))
    )
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if any(p.arrived >= sent and summary in p.models for p in client.patches):
            await asyncio.sleep(0.2)
            return [p for p in client.patches if p.arrived >= sent and summary in p.models]
        await asyncio.sleep(0.02)
    raise AssertionError("no answer to the move")


def test_two_sessions_moved_differently_keep_their_own_drops_and_urls(two_processes):
    """Two students, two drops: each page's summary and URL follow its own slider only (the
    sessions may even live in different processes)."""

    async def check() -> None:
        first = await opened(f"{two_processes.base}/app")
        second = await opened(f"{two_processes.base}/app")
        try:
            moves = [(first, 0.6), (second, 0.95)]
            for client, eps in moves:
                sent = await client.move(client.slider("eps (restitution)"), eps)
                await _answer(client, sent)
            await asyncio.sleep(1.0)  # the URL is rewritten 0.3 s after a change
            for client, eps in moves:
                h1 = twoball.simulate(eps, 0.01, 0.01).h1  # the opening drop's mu and tau_ratio
                texts = [
                    str(client.value(i, "text"))
                    for i, m in client.models.items()
                    if m["name"].endswith("HTML")
                ]
                assert any(f"h1 = {number_text(h1)}" in text for text in texts), eps
                location = next(
                    i for i, m in client.models.items() if m["name"].endswith("Location")
                )
                query = parse_qs(urlparse(str(client.value(location, "search"))).query)
                assert float(query["eps"][0]) == pytest.approx(eps)
        finally:
            await first.close()
            await second.close()

    run(check())


def test_a_move_sends_nothing_to_the_other_pages(two_processes):
    """A page that does nothing receives nothing while another page moves: a move costs the
    server its own page's patch, not one per open page (Panel's process-wide busy spinner
    sent two to every page: 3600 patches a second with 60 pages moving)."""

    async def check() -> None:
        # four idle pages: at least one shares the mover's process (of two) 15 times in 16
        idle = [await opened(f"{two_processes.base}/app") for _ in range(4)]
        mover = await opened(f"{two_processes.base}/app")
        try:
            await asyncio.sleep(1.0)  # the idle pages' own start-up patches (their URLs)
            before = [len(page.patches) for page in idle]
            slider = mover.slider("eps (restitution)")
            for eps in (0.6, 0.7, 0.8):
                await _answer(mover, await mover.move(slider, eps))
            await asyncio.sleep(1.0)
            assert [page.patches[n:] for page, n in zip(idle, before, strict=True)] == [[]] * 4
        finally:
            for page in [*idle, mover]:
                await page.close()

    run(check())


def test_a_release_is_answered_in_one_message_of_float32_data(two_processes):
    """What a move sends: every change of the redraw in one message (each change was a message
    of its own, 16 a move), its plotted columns as float32 (half of float64's bytes)."""

    async def check() -> None:
        client = await opened(f"{two_processes.base}/app")
        try:
            sent = await client.move(client.slider("mu = m2/m1 (log scale)"), -1.5)
            answers = await _answer(client, sent)
            assert len(answers) == 1
            curves = [  # (the apexes' few points keep float64, and their labels are text)
                column
                for event in answers[0].events
                if event.get("kind") == "ColumnDataChanged"
                for _name, column in event["data"]["entries"]
                if isinstance(column, dict) and column["shape"][0] > 100
            ]
            assert len(curves) == 3 and {c["dtype"] for c in curves} == {"float32"}  # t, x1, x2
        finally:
            await client.close()

    run(check())


def test_a_bad_serve_option_is_one_line_and_status_2(tmp_path):
    with socket.socket() as taken:  # a port in use
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        in_use = str(taken.getsockname()[1])
        bad = (
            ["--num-procs", "0"], ["--port", "many"], ["some_app.py"], ["--port", "99999"],
            ["--port", "-5"], ["--address", "999.1.1.1"],
            ["--address", "127.0.0.1", "--port", in_use],
        )  # fmt: skip
        check_each_is_refused(bad, tmp_path)


def check_each_is_refused(bad: tuple, tmp_path) -> None:
    for options in bad:
        done = subprocess.run(
            [str(TWOBALL), "serve", *options], capture_output=True, text=True, cwd=tmp_path
        )
        assert done.returncode == 2, (options, done.stderr)
        lines = done.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("twoball: error: serve:"), lines


@pytest.mark.slow
def test_closed_sessions_give_their_memory_back(artifacts, tmp_path):
    """A school day of classes must not fill the server: opening and closing 60 sessions (on
    every scene but the accuracy study) three times grows the server's memory by at most 10 %
    after the first cycle. (The map's HoloViews hook once kept every session that opened it:
    +65 MB a cycle.)"""
    port = free_port()
    served = Served(twoball_serve(port, 1), port, artifacts / "serve_memory.log", tmp_path)
    scenes = [s for s in SCENES if s != "accuracy"]

    async def cycle() -> None:
        clients = []
        for number in range(60):
            clients.append(await opened(f"{served.base}/app?scene={scenes[number % 4]}"))
        for client in clients:
            await client.close()
        await asyncio.sleep(8.0)  # discarded after 5 s unused, checked every second

    try:
        sizes = []
        for _ in range(3):
            run(cycle())
            sizes.append(rss_mb(served.process.pid))
        assert max(sizes[1:]) <= 1.10 * sizes[0], sizes
    finally:
        served.stop()


@pytest.mark.browser
def test_the_page_says_it_is_working_while_the_server_is_behind(browser, artifacts, tmp_path):
    """A server that is behind (here stopped outright) must not leave stale plots looking
    current: the page dims them and says it is working as soon as the slider is released,
    and clears that when the new plots arrive."""
    port = free_port()
    served = Served(twoball_serve(port, 1), port, artifacts / "serve_behind.log", tmp_path)
    context, page, errors = open_page(browser, f"{served.base}/app", viewport=(1366, 768))
    pending = "() => document.body.classList.contains('twoball-pending')"
    try:
        before = fingerprint(page)
        os.kill(served.process.pid, signal.SIGSTOP)
        try:
            assert press_slider(page, "eps", timeout_ms=500) == -1  # no answer: it is stopped
            assert page.evaluate(pending)
            page.wait_for_timeout(600)  # the dimming waits 0.25 s, so quick answers never show it
            # seen, not only marked: the scene dimmed and the banner shown (the mark alone,
            # without its style sheet, once showed nothing, and a new user saw stale plots)
            shown = page.evaluate(
                """() => [parseFloat(getComputedStyle(document.querySelector('#main')).opacity),
                          getComputedStyle(document.body, '::after').content,
                          parseFloat(getComputedStyle(document.body, '::after').opacity)]"""
            )
            assert shown[0] < 0.6 and "Updating the plots" in shown[1] and shown[2] > 0.9, shown
            page.screenshot(path=artifacts / "server_behind.png")
        finally:
            os.kill(served.process.pid, signal.SIGCONT)
        wait_for_change(page, before)
        page.wait_for_function(f"() => !({pending})()", timeout=20_000)
        page.wait_for_timeout(300)
        assert (
            page.evaluate("parseFloat(getComputedStyle(document.querySelector('#main')).opacity)")
            == 1
        )
        assert errors == []
    finally:
        context.close()
        served.stop()


def _run(command: list[str], cwd: Path) -> subprocess.CompletedProcess:
    done = subprocess.run(command, cwd=cwd, capture_output=True, text=True, timeout=1500)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    return done


@pytest.mark.slow
@pytest.mark.browser
def test_the_installed_package_serves_the_explorer(browser, artifacts, tmp_path):
    """The path of a teacher without a clone: ``pip install 'twoball[app]'`` from the wheel in
    a fresh environment, ``twoball serve`` from another directory on both cores, and a shared
    link opens the same explorer, with its style sheets served locally and nothing asked of
    the network."""
    wheels = tmp_path / "wheels"
    _run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(wheels), "."], REPO)
    (wheel,) = wheels.glob("twoball-*.whl")
    venv = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", str(venv)], tmp_path)
    pins = str(REPO / "requirements" / "app.txt")
    python = str(venv / "bin" / "python")
    _run([python, "-m", "pip", "install", "-q", "-c", pins, f"{wheel}[app]"], tmp_path)
    elsewhere = tmp_path / "classroom"
    elsewhere.mkdir()
    port = free_port()
    command = twoball_serve(port, 2, executable=venv / "bin" / "twoball")
    served = Served(command, port, artifacts / "serve_wheel.log", elsewhere)
    context, page, errors = open_page(
        browser, f"{served.base}/app?scene=map&eps=0.9", viewport=(1366, 768)
    )
    outside: list[str] = []  # requests over the network to anywhere but the server
    page.on(
        "request",
        lambda r: (
            outside.append(r.url)
            if urlparse(r.url).scheme in ("http", "https", "ws", "wss")
            and not r.url.startswith((served.base, served.base.replace("http", "ws")))
            else None
        ),
    )
    try:
        assert "scene=map" in page.url and "eps=0.9" in page.url
        page.screenshot(path=artifacts / "serve_wheel_map.png")
        page.get_by_text("Drop", exact=True).click()
        before = fingerprint(page)
        assert press_slider(page, "mu") > 0
        assert fingerprint(page) != before
        page.reload()
        page.wait_for_timeout(2000)
        assert errors == [] and outside == []
    finally:
        context.close()
        served.stop()
