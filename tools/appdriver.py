"""Serving the app and driving it in Chromium: what the app's tests (tests/app) and the benchmarks
(benchmarks/) share. Neither imports the other; both find this module through tools/ on the path
(pytest: pyproject's pythonpath; a benchmark: its first lines)."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import requests

REPO = Path(__file__).resolve().parents[1]
ARTIFACTS = REPO / "test-artifacts"
CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


def process_tree(pid: int) -> list[int]:
    """``pid`` and its descendants (a server's processes: ``--num-procs`` forks)."""
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            parent = int(stat.rsplit(")", 1)[1].split()[1])
            children.setdefault(parent, []).append(int(entry.name))
    found, todo = [], [pid]
    while todo:
        current = todo.pop()
        found.append(current)
        todo.extend(children.get(current, []))
    return found


def cpu_seconds(pid: int) -> float:
    """User + system CPU of a server's processes so far (/proc)."""
    return sum(cpu_by_process(pid).values())


def cpu_by_process(pid: int) -> dict[int, float]:
    """User + system CPU of each of a server's processes so far (/proc), by process id."""
    seconds = {}
    for process in process_tree(pid):
        try:
            fields = Path(f"/proc/{process}/stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        seconds[process] = (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    return seconds


def rss_mb(pid: int) -> float:
    """Resident memory of a server's processes, in MB (/proc)."""
    pages = 0
    for process in process_tree(pid):
        try:
            pages += int(Path(f"/proc/{process}/statm").read_text().split()[1])
        except OSError:
            continue
    return pages * os.sysconf("SC_PAGE_SIZE") / 2**20


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


def panel_serve(target: str, port: int) -> list[str]:
    """The command serving ``target`` (a directory or file app) on loopback at ``port``."""
    panel = str(Path(sys.executable).parent / "panel")
    return [
        panel, "serve", target, "--address", "127.0.0.1", "--port", str(port),
        "--allow-websocket-origin", f"127.0.0.1:{port}",
    ]  # fmt: skip


def serve(command: list[str], log: Path, cwd: Path = REPO, env: dict | None = None):
    """Start ``command`` (a ``panel serve``), its output in ``log``; returns the process."""
    handle = open(log, "w")  # noqa: SIM115 (closed with the process)
    return subprocess.Popen(
        command, cwd=cwd, stdout=handle, stderr=subprocess.STDOUT, env=env, start_new_session=True
    )


# A fingerprint of every ColumnDataSource in the page: changes when any plotted data changes.
FINGERPRINT_JS = """() => {
  const out = [];
  for (const doc of (window.Bokeh ? Bokeh.documents : [])) {
    for (const model of doc.all_models) {
      if (model.constructor.__name__ !== "ColumnDataSource") continue;
      const data = model.data;
      const columns = data instanceof Map ? [...data.entries()] : Object.entries(data);
      out.push(columns.map(([k, v]) => k + ":" + Array.from(v).slice(0, 40).join(",")).join("|"));
    }
  }
  return out.sort().join("#");
}"""

# Press a key on a slider handle inside the page and resolve, in ms, when the plotted data has
# changed and the next frame has been painted (or -1 after timeout ms).
KEY_TO_PLOT_JS = """async ([index, key, timeout]) => {
  const fingerprint = FINGERPRINT;
  const handles = [];
  const walk = (root) => {
    for (const el of root.querySelectorAll("*")) {
      if (el.classList && el.classList.contains("noUi-handle")) handles.push(el);
      if (el.shadowRoot) walk(el.shadowRoot);
    }
  };
  walk(document);
  const before = fingerprint();
  const start = performance.now();
  handles[index].focus();
  handles[index].dispatchEvent(new KeyboardEvent("keydown", {key: key, bubbles: true}));
  while (performance.now() - start < timeout) {
    await new Promise((resolve) => requestAnimationFrame(resolve));
    if (fingerprint() !== before) {
      await new Promise((resolve) => requestAnimationFrame(resolve));
      return performance.now() - start;
    }
  }
  return -1;
}""".replace("FINGERPRINT", FINGERPRINT_JS)

SLIDERS = {"eps": 0, "mu": 1, "tau_ratio": 2}


def open_page(browser, url: str, *, viewport=(1400, 1000)):
    """A new page at ``url`` with its console errors collected; returns (context, page, errors)."""
    context = browser.new_context(viewport={"width": viewport[0], "height": viewport[1]})
    page = context.new_page()
    errors: list[str] = []
    page.on(
        "console", lambda message: errors.append(message.text) if message.type == "error" else None
    )
    page.on("pageerror", lambda error: errors.append(str(error)))
    page.goto(url)
    wait_for_plots(page)
    return context, page, errors


def fingerprint(page) -> str:
    return page.evaluate(FINGERPRINT_JS)


def wait_for_plots(page, timeout: float = 60.0) -> str:
    """Wait until the page has plotted data and is idle; returns the data's fingerprint."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        current = fingerprint(page)
        if current and ":" in current:
            page.wait_for_timeout(300)
            if fingerprint(page) == current:
                return current
        page.wait_for_timeout(100)
    raise AssertionError("the page showed no plotted data in time")


def wait_for_change(page, before: str, timeout: float = 20.0) -> str:
    """Wait until the plotted data differ from ``before``; returns the new fingerprint."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        current = fingerprint(page)
        if current != before:
            return current
        page.wait_for_timeout(50)
    raise AssertionError("the plotted data did not change")


def press_slider(
    page, name: str | int, key: str = "ArrowRight", timeout_ms: float = 20000
) -> float:
    """Move a slider one step with the keyboard; ms until the plots changed (-1: they did not).
    ``name`` is one of :data:`SLIDERS` or a slider's index in the page."""
    index = name if isinstance(name, int) else SLIDERS[name]
    return page.evaluate(KEY_TO_PLOT_JS, [index, key, timeout_ms])


def slider_titles(page) -> list[str]:
    return page.locator(".bk-slider-title").all_inner_texts()


def start_slider_move(page, name: str, key: str = "ArrowRight", timeout_ms: float = 60000) -> None:
    """Like :func:`press_slider`, without waiting: many pages can move at once."""
    page.evaluate(
        "([index, key, timeout]) => { window.__twoballMove = (" + KEY_TO_PLOT_JS + ")("
        "[index, key, timeout]); }",
        [SLIDERS[name], key, timeout_ms],
    )


def finish_slider_move(page) -> float:
    """The ms a move started by :func:`start_slider_move` took (-1: the plots did not change)."""
    return page.evaluate("() => window.__twoballMove")


# Elements matching a CSS selector anywhere in the page, shadow roots included (Panel renders
# its components inside shadow DOM).
DEEP_QUERY_JS = """(selector) => {
  const found = [];
  const walk = (root) => {
    for (const el of root.querySelectorAll("*")) {
      if (el.matches(selector)) found.push(el);
      if (el.shadowRoot) walk(el.shadowRoot);
    }
  };
  walk(document);
  return found.map((el) => {
    const box = el.getBoundingClientRect();
    return {text: el.innerText || "", href: el.getAttribute("href"), src: el.getAttribute("src"),
            width: box.width, height: box.height, left: box.left, right: box.right,
            top: box.top, bottom: box.bottom, visible: el.checkVisibility(),
            font: parseFloat(getComputedStyle(el).fontSize)};
  });
}"""

# The data of every ColumnDataSource having all the given columns: [{column: [values]}].
SOURCES_JS = """(columns) => {
  const out = [];
  for (const doc of Bokeh.documents) {
    for (const model of doc.all_models) {
      if (model.constructor.__name__ !== "ColumnDataSource") continue;
      const data = model.data instanceof Map ? Object.fromEntries(model.data) : model.data;
      if (columns.every((c) => c in data)) {
        out.push(Object.fromEntries(columns.map((c) => [c, Array.from(data[c])])));
      }
    }
  }
  return out;
}"""


def page_query(page) -> dict[str, str]:
    """The page's URL query, one value a key (the last)."""
    from urllib.parse import parse_qs, urlparse

    return {k: v[-1] for k, v in parse_qs(urlparse(page.url).query).items()}


def deep_query(page, selector: str) -> list[dict]:
    return page.evaluate(DEEP_QUERY_JS, selector)


def sources_with(page, *columns: str) -> list[dict]:
    return page.evaluate(SOURCES_JS, list(columns))


def server_errors(log: Path) -> list[str]:
    """Tracebacks and errors in a server log, apart from Tornado reporting that a page closed by
    a test went away while a message to it was in flight (a client leaving)."""
    import re

    entries = re.split(r"\n(?=\d{4}-\d\d-\d\d \d\d:\d\d:\d\d)", log.read_text())
    return [
        entry
        for entry in entries
        if ("Traceback" in entry or "ERROR" in entry)
        and not ("WebSocketClosedError" in entry and "StreamClosedError" in entry)
    ]
