"""The explorer's first start with an empty numba cache: seconds from ``twoball serve`` (every
core, as a teacher runs it) or ``panel serve app`` (``--panel``: one process, from a clone) to
the first page with plots, then the time each new page takes while the solver compiles in the
background and after (medians), and when the compiled kernels take over: the two-ball solver's
(the page's notice goes), then the stacks' (the server's log).

    .venv/bin/python benchmarks/first_start.py [--panel] [--each]
"""

from __future__ import annotations

import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tools"))

from appdriver import (  # noqa: E402
    CHROMIUM,
    CHROMIUM_ARGS,
    free_port,
    open_page,
    panel_serve,
    serve,
    wait_until_served,
)

NOTICE = "solver is still being compiled"


def main() -> None:
    import argparse

    from playwright.sync_api import sync_playwright

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--panel", action="store_true", help="serve with panel serve app")
    parser.add_argument("--each", action="store_true", help="print each page's time as it opens")
    args = parser.parse_args()
    port = free_port()
    if args.panel:
        command = panel_serve("app", port)
    else:
        twoball = str(Path(sys.executable).parent / "twoball")
        command = [
            twoball, "serve", "--address", "127.0.0.1", "--port", str(port),
            "--allow-websocket-origin", f"127.0.0.1:{port}",
        ]  # fmt: skip
    cache = Path(tempfile.mkdtemp()) / "numba-cache"
    log = Path(tempfile.mkdtemp()) / "server.log"
    started = time.monotonic()
    process = serve(command, log, env={**os.environ, "NUMBA_CACHE_DIR": str(cache)})
    url = f"http://127.0.0.1:{port}/app"
    pages: dict[str, list[float]] = {"compiling": [], "compiled": []}
    try:
        wait_until_served(url, process)
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
            context, page, _ = open_page(browser, url)
            first = time.monotonic() - started
            context.close()
            switched = None
            while len(pages["compiled"]) < 5 and time.monotonic() - started < 900:
                opened = time.monotonic()
                context, page, _ = open_page(browser, url)
                seconds = time.monotonic() - opened
                compiling = page.get_by_text(NOTICE).filter(visible=True).count() > 0
                context.close()
                pages["compiling" if compiling else "compiled"].append(seconds)
                if args.each:
                    print(f"{opened - started:6.1f} s: a page in {seconds:.1f} s"
                          + (" (compiling)" if compiling else ""), flush=True)  # fmt: skip
                if not compiling and switched is None:
                    switched = time.monotonic() - started
            browser.close()
        while "compiled kernels in use" not in log.read_text():  # (the stacks' kernels)
            if time.monotonic() - started > 900 or process.poll() is not None:
                break
            time.sleep(1)
    finally:
        process.terminate()
        process.wait(timeout=30)
    program = Path(command[0]).name
    print(f"first page with plots: {first:.1f} s after {program} serve started (empty cache)")
    for state, times in pages.items():
        if times:
            print(f"a new page while {state}: median {statistics.median(times):.1f} s, "
                  f"max {max(times):.1f} s ({len(times)} pages)")  # fmt: skip
    print(f"pages without the notice from {switched:.0f} s" if switched else "no switch")
    for line in log.read_text().splitlines():  # each stage's kernels in use, from the server
        if "kernels in use after" in line:
            print(line.split(" ", 2)[-1])


if __name__ == "__main__":
    main()
