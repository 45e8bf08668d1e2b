"""Benchmark: a class at once, against ``twoball serve`` on loopback, with protocol clients.

Each simulated student is a :class:`bokehclient.PageClient`: it opens the page as a browser
does (GET, websocket, pull the document) and moves a slider as a browser does on release
(``value``, then ``value_throttled``), with no rendering, so dozens of them fit beside the
server on two cores. Three parts, each bounded in count and time:

1. **Open at once**: ``--burst`` sessions request the page at the same moment; the time until
   each has its document, and the document's size.
2. **Move**: for each count in ``--sessions``, that many sessions each move the eps slider every
   ``--every`` seconds for ``--seconds`` seconds (phases spread evenly); the time from a move to
   the server's last patch for it (the URL's rewrite 0.3 s later is not counted), the server's
   CPU per move (less what it spends idle with the sessions open), resident memory per
   session, and errors.
3. **Play**: ``--play`` sessions press the scene's play button together and play for
   ``--play-seconds`` as the page does (app/animation.py): each frame's number is sent only
   until the frames have come, then the pause sends where the player stopped; the server's CPU
   per frame played (less its idle rate) and what it sends back.
4. **Memory**: ``--cycles`` times, open ``--cycle-sessions`` sessions and close them; the server's
   resident memory after each cycle.

The server (every process of it: ``--num-procs`` forks) is measured from /proc. The baseline in
the same run is a minimal Panel app (one slider, one 10-point line) served the same way.

    .venv/bin/python benchmarks/app_load.py [--sessions 30 60] [--seconds 60] [--num-procs 2]
        [--scene closeup] [--scene stack --slider "mass ratio (each ball / the one below)"]
"""

from __future__ import annotations

import argparse
import asyncio
import os
import signal
import statistics
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tools"))

from appdriver import (  # noqa: E402
    cpu_by_process,
    cpu_seconds,
    free_port,
    rss_mb,
    serve,
    server_errors,
    wait_until_served,
)
from bokehclient import PageClient  # noqa: E402

MINIMAL_APP = """
import numpy as np
import panel as pn
from bokeh.models import ColumnDataSource
from bokeh.plotting import figure

source = ColumnDataSource({"x": np.arange(10.0), "y": np.zeros(10)})
fig = figure(height=300)
fig.line("x", "y", source=source)
slider = pn.widgets.FloatSlider(name="eps (restitution)", start=0, end=1, value=0.5)
slider.param.watch(lambda e: source.data.update(y=np.full(10, e.new)), "value_throttled")
pn.Column(slider, pn.pane.Bokeh(fig)).servable()
"""


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))] if ordered else float("nan")


IDLE_SECONDS = 4.0
FRAME_SECONDS = 0.04  # the players' interval (app/drop.py, app/stack.py)


def not_the_move(client: PageClient) -> set[str]:
    """Models whose patches are not a move's answer: the URL (rewritten 0.3 s later, on
    purpose) and the header's busy spinner (turned off a few hundred ms later)."""
    return {
        model_id
        for model_id, model in client.models.items()
        if model["name"].endswith("Location")
        or "loader" in (model.get("attributes", {}).get("css_classes") or [])
    }


def last_patch_after(client: PageClient, sent: float, until: float, ignore: set[str]) -> float:
    """Seconds from a move to the last patch that followed it (before ``until``), not counting
    patches that touch only the models in ``ignore`` (the URL); NaN if none came."""
    times = [
        p.arrived for p in client.patches if sent <= p.arrived < until and not p.models <= ignore
    ]
    return max(times) - sent if times else float("nan")


async def open_burst(url: str, count: int) -> list[PageClient]:
    clients = [PageClient(url) for _ in range(count)]
    await asyncio.gather(*(c.open(timeout=120) for c in clients))
    return clients


async def settled(pid: int, quiet: float = 0.5, timeout: float = 120.0) -> None:
    """Wait until the server spends under 4 % of a core for ``quiet`` seconds."""
    deadline = time.monotonic() + timeout
    last = cpu_seconds(pid)
    while time.monotonic() < deadline:
        await asyncio.sleep(quiet)
        now = cpu_seconds(pid)
        if now - last < 0.04 * quiet:
            return
        last = now


async def idle_rate(pid: int) -> float:
    """The server's CPU seconds a second with the sessions open and nothing asked of it, over
    :data:`IDLE_SECONDS`: taken off what a part measures."""
    start = cpu_seconds(pid)
    await asyncio.sleep(IDLE_SECONDS)
    return (cpu_seconds(pid) - start) / IDLE_SECONDS


async def moving(url: str, count: int, seconds: float, every: float, pid: int, slider: str) -> dict:
    """``count`` sessions, each moving the slider titled ``slider`` every ``every`` s for
    ``seconds`` s, through ten values inside its range."""
    rss_before = rss_mb(pid)
    clients = [PageClient(url) for _ in range(count)]
    for client in clients:  # one after another, as a class does over a few seconds
        await client.open(timeout=120)
    rss_open = rss_mb(pid)
    latencies: list[float] = []
    missing = 0
    idle = await idle_rate(pid)
    cpu_start, started = cpu_seconds(pid), time.monotonic()

    async def student(index: int, client: PageClient) -> None:
        nonlocal missing
        slider_id = client.slider(slider)
        low, high = (client.models[slider_id]["attributes"][k] for k in ("start", "end"))
        ignored = not_the_move(client)
        await asyncio.sleep(every * index / count)
        start = time.monotonic()
        moves = 0
        while time.monotonic() - start < seconds:
            value = low + (high - low) * (0.3 + 0.6 * ((index * 7 + moves) % 10) / 10)
            sent = await client.move(slider_id, value)
            moves += 1
            await asyncio.sleep(every)
            latency = last_patch_after(client, sent, time.monotonic(), ignored)
            if latency != latency:
                missing += 1
            else:
                latencies.append(latency)

    await asyncio.gather(*(student(i, c) for i, c in enumerate(clients)))
    cpu = cpu_seconds(pid) - cpu_start - idle * (time.monotonic() - started)
    moves = len(latencies) + missing
    errors = sum(len(c.errors) for c in clients)
    for client in clients:
        await client.close()
    return {
        "sessions": count,
        "moves": moves,
        "p50_ms": 1e3 * percentile(latencies, 0.5),
        "p95_ms": 1e3 * percentile(latencies, 0.95),
        "max_ms": 1e3 * max(latencies, default=float("nan")),
        "no_patch": missing,
        "errors": errors,
        "open_p50_ms": 1e3 * statistics.median(c.opened for c in clients),
        "cpu_per_move_ms": 1e3 * cpu / max(moves, 1),
        "mb_per_session": (rss_open - rss_before) / count,
    }


async def playing(url: str, count: int, seconds: float, pid: int) -> dict:
    """``count`` sessions playing the scene's animation at once for ``seconds`` s."""
    clients = [PageClient(url) for _ in range(count)]
    for client in clients:
        await client.open(timeout=120)
    await settled(pid)
    idle = await idle_rate(pid)
    received = [client.received() for client in clients]
    cpu_start, started = cpu_seconds(pid), time.monotonic()

    async def student(client: PageClient) -> int:
        """Play for ``seconds`` as the page does (app/animation.py): press play, send each
        frame's number until the frames have come, then nothing until the pause, which sends
        where the player stopped; the number of frames played."""
        player = next(i for i, m in client.models.items() if m["name"].endswith("Player"))
        end = client.models[player]["attributes"]["end"]
        asked = len(client.patches)
        await client.set(player, {"direction": 1})
        frame = played = 0
        while time.monotonic() - started < seconds:
            frame = frame + 1 if frame < end else 0
            if not any(
                event.get("kind") == "ColumnDataChanged"
                for patch in client.patches[asked:]
                for event in patch.events
            ):  # (the frames not yet here)
                await client.set(player, {"value": frame})  # (two messages, as Panel's
                await client.set(player, {"value_throttled": frame})  # player sends them)
            played += 1
            await asyncio.sleep(FRAME_SECONDS)
        await client.set(player, {"direction": 0})
        await client.set(player, {"value_throttled": frame})
        return played

    frames = sum(await asyncio.gather(*(student(c) for c in clients)))
    elapsed = time.monotonic() - started
    await asyncio.sleep(1.0)  # the last frames' answers
    cpu = cpu_seconds(pid) - cpu_start - idle * elapsed
    sent_back = sum(c.received() - r for c, r in zip(clients, received, strict=True))
    errors = sum(len(c.errors) for c in clients)
    await _close(clients)
    return {
        "fps": frames / elapsed / count,
        "cpu_ms_per_frame": 1e3 * cpu / frames,
        "load": cpu / elapsed,
        "bytes_per_frame": sent_back / frames,
        "errors": errors,
    }


async def cycles(url: str, count: int, rounds: int, pid: int, settle: float) -> list[float]:
    """Resident memory (MB) before and after each of ``rounds`` cycles of ``count`` sessions
    opened and closed."""
    sizes = [rss_mb(pid)]
    for _ in range(rounds):
        clients = [PageClient(url) for _ in range(count)]
        for client in clients:
            await client.open(timeout=120)
        for client in clients:
            await client.close()
        await asyncio.sleep(settle)  # the server discards closed sessions
        sizes.append(rss_mb(pid))
    return sizes


def start_server(
    command: list[str],
    port: int,
    log: Path,
    processes: int,
    compiles: bool,
    env: dict | None = None,
):
    """Start the server and wait until it serves, and (``compiles``) until each of its
    processes has its compiled kernels in use: their loading from the disk cache, in a thread
    and a child process, is a start's cost, not a move's."""
    process = serve(command, log, env=env)
    wait_until_served(f"http://127.0.0.1:{port}/liveness", process, timeout=300)
    deadline = time.monotonic() + 600
    while compiles and log.read_text().count("compiled kernels in use") < processes:
        if time.monotonic() > deadline:
            raise RuntimeError("the server's kernels were not in use within 600 s")
        time.sleep(0.5)
    return process


def twoball_serve(port: int, num_procs: int) -> list[str]:
    return [
        str(Path(sys.executable).parent / "twoball"), "serve", "--address", "127.0.0.1",
        "--port", str(port), "--num-procs", str(num_procs),
        # closed sessions are discarded within 6 s (Bokeh's defaults: 15-32 s); not sooner, as
        # a session is "unused" from its websocket's opening to its first pull, which under
        # overload took over a second
        "--check-unused-sessions", "1000", "--unused-session-lifetime", "5000",
    ]  # fmt: skip


def minimal_serve(port: int, num_procs: int, script: Path) -> list[str]:
    return [
        str(Path(sys.executable).parent / "panel"), "serve", str(script), "--address",
        "127.0.0.1", "--port", str(port), "--num-procs", str(num_procs), "--liveness",
        "--allow-websocket-origin", f"127.0.0.1:{port}", "--reuse-sessions",
        "--check-unused-sessions", "1000", "--unused-session-lifetime", "5000",
    ]  # fmt: skip


async def run(label: str, command: list[str], url: str, port: int, args, log: Path) -> None:
    process = start_server(command, port, log, args.num_procs, label == "twoball")
    try:
        await _close(await open_burst(url, 2))  # each process's first page (imports, caches)
        await asyncio.sleep(1.0)
        idle = rss_mb(process.pid)
        cpu_start = cpu_seconds(process.pid)
        each_start = cpu_by_process(process.pid)
        started = time.monotonic()
        burst = await open_burst(url, args.burst)
        wall = time.monotonic() - started
        await settled(process.pid)  # the scenes that follow the documents, the URLs' rewrite
        cpu = cpu_seconds(process.pid) - cpu_start
        # how the burst was shared among the server's processes (the parent only waits)
        shares = sorted(
            (now - each_start.get(pid, 0.0) for pid, now in cpu_by_process(process.pid).items()),
            reverse=True,
        )[: args.num_procs]
        opens = [c.opened for c in burst]
        complete = [c.complete() for c in burst]
        print(
            f"{label}: idle {idle:.0f} MB; {args.burst} sessions opened at once: all documents "
            f"in {max(opens):.2f} s (median {statistics.median(opens):.2f} s, wall {wall:.2f} s),"
            f" pages complete (their last message) in {max(complete):.2f} s (median "
            f"{statistics.median(complete):.2f} s); "
            f"server CPU {1e3 * cpu / args.burst:.0f} ms per session (by process: "
            f"{' / '.join(f'{share:.1f}' for share in shares)} s); first document "
            f"{burst[0].document_bytes / 1e3:.0f} kB ({len(burst[0].models)} models)",
            flush=True,
        )
        await _close(burst)
        await asyncio.sleep(2.0)
        for count in args.sessions:
            slider = args.slider if label == "twoball" else "eps (restitution)"
            row = await moving(url, count, args.seconds, args.every, process.pid, slider)
            print(
                f"{label}: {count} sessions moving every {args.every:g} s for {args.seconds:g} "
                f"s: {row['moves']} moves, move to last patch p50 {row['p50_ms']:.0f} ms, p95 "
                f"{row['p95_ms']:.0f} ms, max {row['max_ms']:.0f} ms; no patch "
                f"{row['no_patch']}, errors {row['errors']}; open p50 "
                f"{row['open_p50_ms']:.0f} ms; server CPU {row['cpu_per_move_ms']:.1f} ms per "
                f"move; {row['mb_per_session']:.1f} MB per open session",
                flush=True,
            )
            await asyncio.sleep(2.0)
        if args.play and label == "twoball":
            row = await playing(url, args.play, args.play_seconds, process.pid)
            print(
                f"{label}: {args.play} sessions playing the animation for "
                f"{args.play_seconds:g} s, {row['fps']:.1f} frames a second each: server CPU "
                f"{row['cpu_ms_per_frame']:.3f} ms a frame played ({row['load']:.2f} cores in "
                f"all), {row['bytes_per_frame']:.0f} bytes to the page a frame; errors "
                f"{row['errors']}",
                flush=True,
            )
        if args.cycles:
            sizes = await cycles(url, args.cycle_sessions, args.cycles, process.pid, 8.0)
            growth = [f"{100 * (b / sizes[1] - 1):+.1f} %" for b in sizes[2:]]
            print(
                f"{label}: resident memory over {args.cycles} cycles of {args.cycle_sessions} "
                f"sessions opened and closed: {' -> '.join(f'{s:.0f}' for s in sizes)} MB "
                f"(after the first cycle: {', '.join(growth)})",
                flush=True,
            )
        errors = server_errors(log)
        print(f"{label}: server log errors: {len(errors)}", flush=True)
        for error in errors[:2]:
            print("   ", error[:1500], flush=True)
    finally:
        # the whole process group (serve started it in a session of its own): a plain
        # `panel serve --num-procs 2` leaves its forked children serving when only the first
        # process is stopped
        os.killpg(process.pid, signal.SIGTERM)
        process.wait(timeout=30)


async def _close(clients: list[PageClient]) -> None:
    for client in clients:
        await client.close()


async def measure(args) -> None:
    with tempfile.TemporaryDirectory() as folder:
        if not args.no_baseline:
            script = Path(folder) / "minimal.py"
            script.write_text(MINIMAL_APP)
            port = free_port()
            url = f"http://127.0.0.1:{port}/minimal"
            command = minimal_serve(port, args.num_procs, script)
            await run("minimal", command, url, port, args, Path(folder) / "minimal.log")
        port = free_port()
        url = f"http://127.0.0.1:{port}/app?scene={args.scene}"
        command = twoball_serve(port, args.num_procs)
        await run("twoball", command, url, port, args, Path(folder) / "twoball.log")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sessions", type=int, nargs="*", default=[30, 60])
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--every", type=float, default=2.0)
    parser.add_argument("--burst", type=int, default=30)
    parser.add_argument("--cycles", type=int, default=3)
    parser.add_argument("--cycle-sessions", type=int, default=60)
    parser.add_argument("--play", type=int, default=0, help="sessions playing at once")
    parser.add_argument("--play-seconds", type=float, default=10.0)
    parser.add_argument("--num-procs", type=int, default=len(os.sched_getaffinity(0)))
    parser.add_argument("--scene", default="drop")
    parser.add_argument(
        "--slider", default="eps (restitution)", help="the title of the slider moved (twoball)"
    )
    parser.add_argument("--no-baseline", action="store_true")
    args = parser.parse_args()
    from twoball import warmup

    warmup.warm_up()  # the disk cache filled: the server starts on compiled kernels
    asyncio.run(measure(args))
    print(f"(--num-procs {args.num_procs}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f})")


if __name__ == "__main__":
    main()
