"""The first start after an install, with nothing compiled: pages are served at once on the
kernels' Python functions, saying that the solver is being compiled, and the machine code takes
over as the compiler, in another process, is done with each stage: the two-ball solver's first,
then the stacks' (app/app_hooks.py, twoball/warmup.py).

How long each step takes is measured by benchmarks/first_start.py, not asserted here."""

from __future__ import annotations

import os
import time

import pytest
from appdriver import free_port, open_page, panel_serve, serve, wait_until_served

pytestmark = [pytest.mark.browser, pytest.mark.slow]

NOTICE = "solver is still being compiled"


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
    assert text.index("two-ball kernels in use") < text.index("stacks kernels in use")
    assert text.index("stacks kernels in use") < text.index("compiled kernels in use")
