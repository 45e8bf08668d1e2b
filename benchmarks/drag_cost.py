"""Benchmark: the server's CPU for each step of a slider's drag, as Bokeh's slider sent them.

Without app/static/drag.js a slider sends its ``value`` at every step of a drag (30-60 a
second), which the explorer does not read (it reads the release, ``value_throttled``). One
protocol client (tools/bokehclient.py) on ``twoball serve --num-procs 1`` sends ``--steps``
such values 20 ms apart; the server's CPU per step, less its idle rate. With drag.js a page
sends none of them (tests/app/test_app_browser.py checks it:
``test_a_drag_stays_in_the_page_until_the_release``).

    .venv/bin/python benchmarks/drag_cost.py [--steps 400]
"""

from __future__ import annotations

import argparse
import asyncio
import os
import signal
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tools"))  # (benchmarks/ is on the path: app_load)

from app_load import idle_rate, start_server, twoball_serve  # noqa: E402
from appdriver import cpu_seconds, free_port  # noqa: E402
from bokehclient import PageClient  # noqa: E402

STEP_SECONDS = 0.02


async def measure(url: str, pid: int, steps: int) -> float:
    """ms of server CPU per drag step."""
    client = PageClient(url)
    await client.open()
    await asyncio.sleep(4.0)  # the page's scene and URL settled
    slider = client.slider("eps (restitution)")
    idle = await idle_rate(pid)
    started, cpu_start = time.monotonic(), cpu_seconds(pid)
    for step in range(steps):
        await client.set(slider, {"value": 0.5 + 0.4 * (step % 40) / 40})
        await asyncio.sleep(STEP_SECONDS)
    await asyncio.sleep(1.0)
    cpu = cpu_seconds(pid) - cpu_start - idle * (time.monotonic() - started)
    await client.close()
    return 1e3 * cpu / steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=400)
    args = parser.parse_args()
    port = free_port()
    with tempfile.TemporaryDirectory() as folder:
        process = start_server(twoball_serve(port, 1), port, Path(folder) / "serve.log", 1, True)
        try:
            url = f"http://127.0.0.1:{port}/app?scene=drop"
            per_step = asyncio.run(measure(url, process.pid, args.steps))
        finally:
            os.killpg(process.pid, signal.SIGTERM)
            process.wait(timeout=30)
    print(
        f"server CPU per drag step: {per_step:.2f} ms ({args.steps} steps, "
        f"{1 / STEP_SECONDS:.0f} a second; load {os.getloadavg()[0]:.2f}, {os.cpu_count()} cores)"
    )


if __name__ == "__main__":
    main()
