"""Benchmark: the Stack scene's slider latency with the Hertz force against the linear one,
measured in the same run (the target: the Hertz median within 1.3 times the linear).

One ``twoball serve`` on loopback; one protocol client (tools/bokehclient.py, as
benchmarks/app_load.py: the page opened as a browser does, the slider moved as on release, no
rendering) per configuration, force x balls. The configurations take turns, one move each per
round, so that a change in the machine's load falls on all of them alike. The latency is the
time from a move to the server's last patch for it (the URL's rewrite and the busy spinner not
counted).

    .venv/bin/python benchmarks/stack_force_latency.py [--balls 3 6] [--moves 30] [--every 1.5]
"""

from __future__ import annotations

import argparse
import asyncio
import statistics
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tools"))
sys.path.insert(0, str(REPO / "benchmarks"))

from app_load import last_patch_after, not_the_move, start_server, twoball_serve  # noqa: E402
from appdriver import free_port  # noqa: E402
from bokehclient import PageClient  # noqa: E402

SLIDER = "eps"  # the Stack scene's restitution slider (the two-ball one is "eps (restitution)")


async def measure(args) -> dict[tuple[str, int], list[float]]:
    with tempfile.TemporaryDirectory() as folder:
        port = free_port()
        process = start_server(twoball_serve(port, 1), port, Path(folder) / "log", 1, True)
        try:
            configs = [(force, n) for n in args.balls for force in ("linear", "hertz")]
            clients = {}
            for force, n in configs:
                url = f"http://127.0.0.1:{port}/app?scene=stack&N={n}&force={force}"
                clients[force, n] = client = PageClient(url)
                await client.open(timeout=120)
            latencies = {config: [] for config in configs}
            for move in range(args.moves):
                for config in configs:
                    client = clients[config]
                    slider = client.slider(SLIDER)
                    low, high = (client.models[slider]["attributes"][k] for k in ("start", "end"))
                    value = low + (high - low) * (0.3 + 0.6 * (move % 10) / 10)
                    sent = await client.move(slider, round(value, 2))
                    await asyncio.sleep(args.every)
                    latency = last_patch_after(client, sent, time.monotonic(), not_the_move(client))
                    if move and latency == latency:  # (the first move of each: warm-up)
                        latencies[config].append(latency)
            for client in clients.values():
                await client.close()
            return latencies
        finally:
            process.terminate()
            process.wait(timeout=30)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--balls", type=int, nargs="*", default=[3, 6])
    parser.add_argument("--moves", type=int, default=30)
    parser.add_argument("--every", type=float, default=1.5)
    args = parser.parse_args()
    from twoball.warmup import warm_up

    warm_up()
    latencies = asyncio.run(measure(args))
    for n in args.balls:
        medians = {f: 1e3 * statistics.median(latencies[f, n]) for f in ("linear", "hertz")}
        for force in ("linear", "hertz"):
            values = sorted(latencies[force, n])
            p95 = 1e3 * values[min(len(values) - 1, int(0.95 * len(values)))]
            print(
                f"N = {n}, {force}: {len(values)} moves, median {medians[force]:.0f} ms, "
                f"p95 {p95:.0f} ms",
                flush=True,
            )
        print(f"N = {n}: hertz / linear median = {medians['hertz'] / medians['linear']:.2f}")


if __name__ == "__main__":
    main()
