"""The first start after an install, with nothing compiled: pages are served at once on the
kernels' Python functions, saying that the solver is being compiled, and the machine code takes
over as the compiler, in another process, is done with each stage: the two-ball solver's first,
then the stacks' (app/app_hooks.py, twoball/warmup.py).

How long each step takes is measured by benchmarks/first_start.py, not asserted here."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest
from appdriver import free_port, open_page, panel_serve, serve, wait_until_served

pytestmark = [pytest.mark.browser, pytest.mark.slow]

NOTICE = "solver is still being compiled"

# Every scene's page, built in a process of its own on the cache the first start's compiler
# filled; then each kernel signature that was not in the cache (compiled by this process, as a
# server would compile it for the first page to take its path, the page waiting)
PAGES_FROM_THE_CACHE = """
import importlib
from bokeh.document import Document
from numba.core.registry import CPUDispatcher
from panel.io.state import set_curdoc
from app.explorer import Explorer
from twoball import jit
queries = [{"scene": s} for s in ("drop", "closeup", "map", "accuracy", "stack")]
queries += [{"scene": "stack", "force": "hertz"}, {"scene": "map", "map_force": "hertz"}]
for query in queries:
    with set_curdoc(Document()):
        Explorer(query).page()
for name in jit.KERNEL_MODULES:
    for attribute, value in vars(importlib.import_module(name)).items():
        if isinstance(value, CPUDispatcher) and value.stats.cache_misses:
            print(name, attribute, len(value.stats.cache_misses))
"""


def page_says_compiling(browser, url: str) -> bool:
    """Open a page, wait for its plots; whether it says that the solver is being compiled."""
    context, page, errors = open_page(browser, url)
    compiling = page.get_by_text(NOTICE).filter(visible=True).count() > 0
    context.close()
    assert errors == []
    return compiling


def test_first_start_serves_plots_while_the_solver_compiles(browser, artifacts, tmp_path):
    port = free_port()
    log = artifacts / "first_start_server.log"
    cache = tmp_path / "empty-numba-cache"
    process = serve(
        panel_serve("app", port), log, env={**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    )
    url = f"http://127.0.0.1:{port}/app"
    try:
        wait_until_served(url, process)
        # plots before the compiler is done: the page says it is compiling
        context, page, errors = open_page(browser, url)
        assert page.get_by_text(NOTICE).filter(visible=True).count() == 1
        page.screenshot(path=artifacts / "first_start.png")
        context.close()
        assert errors == []
        deadline = time.monotonic() + 600
        while page_says_compiling(browser, url):
            assert time.monotonic() < deadline, "the solver was not compiled within 600 s"
            time.sleep(2)
        assert any(cache.rglob("*.nbi")), "the compiler wrote no cache"
        # the notice goes with the two-ball solver's kernels; the stacks' follow
        assert "two-ball kernels in use" in log.read_text()
        while "compiled kernels in use" not in log.read_text():
            assert time.monotonic() < deadline, "the stacks were not compiled within 600 s"
            time.sleep(2)
    finally:
        process.terminate()
        process.wait(timeout=30)
    text = log.read_text()
    assert "Traceback" not in text, text[-3000:]
    # the compiler compiled what the pages use: nothing is left for a page to compile (the
    # first drop page after the two-ball stage compiled the heights-only and sampling paths,
    # and waited 10.8 s: benchmarks/first_start.py)
    built = subprocess.run(
        [sys.executable, "-c", PAGES_FROM_THE_CACHE],
        env={**os.environ, "NUMBA_CACHE_DIR": str(cache)},
        cwd=Path(__file__).resolve().parents[2],  # (the app's package)
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert built.returncode == 0, built.stderr[-3000:]
    assert built.stdout == "", f"kernels compiled by a page, not by the warm-up:\n{built.stdout}"
    assert text.index("two-ball kernels in use") < text.index("stacks kernels in use")
    assert text.index("stacks kernels in use") < text.index("compiled kernels in use")
