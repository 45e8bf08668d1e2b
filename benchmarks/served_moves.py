"""Benchmark: the server's CPU for one page's slider moves, served (the target: 10 ms of server
CPU a move, one page alone).

Starts ``twoball serve --num-procs 1``, opens one page of each ``--scene`` with a protocol client
(tools/bokehclient.py), and moves its eps slider (the Stack's own eps there) every 0.05 s, as a
browser sends a release (value and value_throttled), ``--moves`` times over 0.55-0.95. The CPU
is the server process's (/proc), less its idle CPU over as long (measured for 5 s before), per
move. Run it on an otherwise idle machine: with other work on both cores it gave less CPU a
move, for reasons not found (docs/performance.md, "Twelfth session").

    .venv/bin/python benchmarks/served_moves.py [--moves 200] [--scene drop closeup stack]

``--baseline DIR``: a second server from another checkout DIR (e.g. ``git worktree add DIR
508fba8``) beside this tree's, one page on each, moved in turn (the same values, 0.05 s apart),
so that the machine's state falls on both alike; the CPU of each server's threads in
nanoseconds (/proc/PID/task/*/schedstat, not /proc's 10 ms ticks) over ``--blocks`` blocks of
``--per-block`` moves, and the median of the blocks' ratios, this tree over the baseline. On
this machine one server's CPU a move swung by 15 % between runs minutes apart; the ratio by 2-3 %.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import statistics
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


def thread_cpu_seconds(pid: int) -> float:
    """CPU of all of a process's threads so far, to the nanosecond (/proc/PID/task/*/schedstat;
    a thread that has ended no longer counts: the blocks' ratios use medians)."""
    total = 0
    for thread in os.listdir(f"/proc/{pid}/task"):
        try:
            total += int(Path(f"/proc/{pid}/task/{thread}/schedstat").read_text().split()[0])
        except OSError:
            continue
    return total / 1e9


def served_from(checkout: Path | None, port: int, log: Path):
    """``twoball serve --num-procs 1`` from this tree, or from another ``checkout`` (its
    ``twoball`` and its app as ``twoball_app``, through PYTHONPATH and a link in a temporary
    directory), its kernels compiled."""
    env = None
    if checkout is not None:
        aliases = Path(tempfile.mkdtemp())
        (aliases / "twoball_app").symlink_to(checkout.resolve() / "app")
        env = {**os.environ, "PYTHONPATH": f"{checkout.resolve()}{os.pathsep}{aliases}"}
    return app_load.start_server(app_load.twoball_serve(port, 1), port, log, 1, True, env)


async def paired(scene: str, baseline: Path, blocks: int, per_block: int) -> list[float]:
    """This tree's server CPU a move over the baseline's, one ratio a block of moves."""
    servers = {}
    try:
        for checkout in (None, baseline):
            port = free_port()
            log = Path(tempfile.mkdtemp()) / "server.log"
            servers[checkout] = (port, served_from(checkout, port, log))
        pages = []
        for port, process in servers.values():
            client = PageClient(f"http://127.0.0.1:{port}/app?scene={scene}")
            await client.open()
            pages.append((client, client.slider(SLIDERS.get(scene, "eps (restitution)")), process))
        for index in range(10):  # (each scene's first moves: its caches)
            for client, slider, _ in pages:
                await client.move(slider, 0.5 + 0.01 * index)
                await asyncio.sleep(0.05)
        await asyncio.sleep(2)
        ratios, move = [], 0
        for _ in range(blocks):
            start = [thread_cpu_seconds(process.pid) for _, _, process in pages]
            for _ in range(per_block):
                value = 0.55 + 0.4 * ((move * 37) % 100) / 100
                move += 1
                for client, slider, _ in pages:
                    await client.move(slider, value)
                    await asyncio.sleep(0.05)
            await asyncio.sleep(0.5)
            spent = [
                thread_cpu_seconds(p.pid) - s for (_, _, p), s in zip(pages, start, strict=True)
            ]
            ratios.append(spent[0] / spent[1])
        for client, _, _ in pages:
            await client.close()
        return ratios
    finally:
        for _, process in servers.values():
            process.terminate()
            process.wait(timeout=30)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--moves", type=int, default=200)
    parser.add_argument("--scene", nargs="*", default=["drop", "closeup", "stack"])
    parser.add_argument("--baseline", type=Path, help="another checkout, served beside this one")
    parser.add_argument("--blocks", type=int, default=8)
    parser.add_argument("--per-block", type=int, default=50)
    args = parser.parse_args()
    if args.baseline is not None:
        for scene in args.scene:
            ratios = asyncio.run(paired(scene, args.baseline, args.blocks, args.per_block))
            print(
                f"{scene}: server CPU a move, this tree over {args.baseline}: median of "
                f"{len(ratios)} blocks {statistics.median(ratios):.3f} "
                f"(blocks {min(ratios):.3f} to {max(ratios):.3f})"
            )
        return
    for scene in args.scene:
        cost = asyncio.run(per_move(scene, args.moves))
        print(f"{scene}: served, one page, server CPU per eps move: {cost:.1f} ms")


if __name__ == "__main__":
    main()
