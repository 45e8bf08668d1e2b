"""Benchmark: the server's CPU for one page's slider moves, served (the target: 10 ms of server
CPU a move, one page alone).

Starts ``twoball serve --num-procs 1``, opens one page of each ``--scene`` with a protocol client
(tools/bokehclient.py), and moves its eps slider (the Stack's own eps there) every 0.05 s, as a
browser sends a release (value and value_throttled), ``--moves`` times over 0.55-0.95. The CPU
is the server process's (/proc), less its idle CPU over as long (measured for 5 s before), per
move. Run it on an otherwise idle machine: with other work on both cores it gave less CPU a
move, for reasons not found (docs/performance.md, "Twelfth session").

    .venv/bin/python benchmarks/served_moves.py [--moves 200] [--scene drop closeup stack]
"""

from __future__ import annotations

import argparse
import asyncio
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "benchmarks"))
sys.path.insert(0, str(REPO / "tools"))

import app_load  # noqa: E402
from appdriver import cpu_seconds, free_port  # noqa: E402
from bokehclient import PageClient  # noqa: E402

SLIDERS = {"stack": "eps"}  # (the other scenes: the two-ball sliders' "eps (restitution)")


async def per_move(scene: str, moves: int) -> float:
    """Server CPU ms per eps move of one ``scene`` page, idle CPU subtracted."""
    port = free_port()
    log = Path(tempfile.mkdtemp()) / "server.log"
    process = app_load.start_server(app_load.twoball_serve(port, 1), port, log, 1, True)
    try:
        client = PageClient(f"http://127.0.0.1:{port}/app?scene={scene}")
        await client.open()
        slider = client.slider(SLIDERS.get(scene, "eps (restitution)"))
        for index in range(10):  # (the scene's first moves: its caches)
            await client.move(slider, 0.5 + 0.01 * index)
            await asyncio.sleep(0.05)
        await asyncio.sleep(2)
        start = cpu_seconds(process.pid)
        await asyncio.sleep(5)
        idle = (cpu_seconds(process.pid) - start) / 5
        start, began = cpu_seconds(process.pid), time.monotonic()
        for index in range(moves):
            await client.move(slider, 0.55 + 0.4 * ((index * 37) % 100) / 100)
            await asyncio.sleep(0.05)
        await asyncio.sleep(1)
        spent = cpu_seconds(process.pid) - start - idle * (time.monotonic() - began)
        await client.close()
        return 1e3 * spent / moves
    finally:
        process.terminate()
        process.wait(timeout=30)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--moves", type=int, default=200)
    parser.add_argument("--scene", nargs="*", default=["drop", "closeup", "stack"])
    args = parser.parse_args()
    for scene in args.scene:
        cost = asyncio.run(per_move(scene, args.moves))
        print(f"{scene}: served, one page, server CPU per eps move: {cost:.1f} ms")


if __name__ == "__main__":
    main()
