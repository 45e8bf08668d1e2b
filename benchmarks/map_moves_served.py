"""Benchmark: what one eps move on the map costs a served page: the bytes the page receives on
its socket (compressed, as a browser's permessage-deflate connection gets them) and the server's
CPU, the map cube's and a Hertz cube's.

Starts ``twoball serve --num-procs 1``, opens one page per map with a protocol client
(tools/bokehclient.py), and moves its eps slider back and forth over ``--moves`` values, each
move waited for (its last patch, then 0.3 s). The bytes a median over the moves, the CPU a
mean (/proc counts it in 10 ms ticks).

    .venv/bin/python benchmarks/map_moves_served.py [--moves 20]
"""

from __future__ import annotations

import argparse
import asyncio
import statistics
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "benchmarks"))
sys.path.insert(0, str(REPO / "tools"))

import app_load  # noqa: E402
from appdriver import cpu_seconds, free_port  # noqa: E402
from bokehclient import PageClient  # noqa: E402

MAPS = {"map": "scene=map&eps=0.6", "map hertz": "scene=map&map_force=hertz&eps=0.6"}
# (each a move from the one before, the first from the page's 0.6: a move to the value the
# slider has is none, and the server sends nothing)
EPS = (0.7, 0.8, 0.9, 0.95, 0.85, 0.75, 0.65, 0.55, 0.5, 0.6)


async def moves(base: str, query: str, count: int, pid: int) -> tuple[int, list[int], list[float]]:
    """The page's first document (wire bytes), then per eps move its wire bytes and the server's
    CPU ms."""
    client = PageClient(f"{base}/app?{query}")
    await client.open()
    await asyncio.sleep(2.0)  # (its onload callbacks: the scene drawn for the page)
    slider = client.slider("eps (restitution)")
    sizes, costs = [], []
    for i in range(count + 2):
        received, cpu, patches = client.received(), cpu_seconds(pid), len(client.patches)
        await client.move(slider, EPS[i % len(EPS)])
        for _ in range(3000):  # (at most 30 s)
            if len(client.patches) > patches:
                break
            await asyncio.sleep(0.01)
        else:
            raise TimeoutError(f"no patch after moving eps to {EPS[i % len(EPS)]}")
        await asyncio.sleep(0.3)  # (the move's last patch: nothing more for 0.3 s)
        if i >= 2:  # (the first two: the process's first slices read)
            sizes.append(client.received() - received)
            costs.append(1e3 * (cpu_seconds(pid) - cpu))
    await client.close()
    return client.document_wire_bytes, sizes, costs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--moves", type=int, default=20)
    args = parser.parse_args()
    port = free_port()
    log = Path(tempfile.mkdtemp()) / "server.log"
    process = app_load.start_server(app_load.twoball_serve(port, 1), port, log, 1, True)
    try:
        print(f"one eps move on a served map, median of {args.moves}")
        for name, query in MAPS.items():
            first, sizes, costs = asyncio.run(
                moves(f"http://127.0.0.1:{port}", query, args.moves, process.pid)
            )
            print(
                f"{name:10s} first document {first / 1e3:6.1f} kB on the wire; a move "
                f"{statistics.median(sizes) / 1e3:6.1f} kB on the wire, "
                f"{statistics.mean(costs):5.1f} ms of server CPU (mean: /proc counts 10 ms ticks)"
            )
    finally:
        process.terminate()
        process.wait(timeout=30)


if __name__ == "__main__":
    main()
