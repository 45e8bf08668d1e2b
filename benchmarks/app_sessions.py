"""Benchmark: the server with 20 sessions open at once, each moving sliders.

Serves the app (``panel serve app``, one process), opens 20 Chromium pages on the drop scene,
then for a bounded number of rounds moves one slider in every page at once and waits until all
20 have updated plots. Reports the server's resident memory (idle, with 20 sessions, after the
rounds), its CPU time per move, the per-page latency and the wall time of a round.
Chromium runs on the same 2-core machine as the server, so this is a pessimistic figure.

    .venv/bin/python benchmarks/app_sessions.py [--sessions 20] [--rounds 10]
"""

from __future__ import annotations

import argparse
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
    cpu_seconds,
    finish_slider_move,
    free_port,
    open_page,
    panel_serve,
    rss_mb,
    serve,
    server_errors,
    start_slider_move,
    wait_until_served,
)


def server_errors_in(log: str) -> list[str]:
    with tempfile.NamedTemporaryFile("w", suffix=".log") as file:
        file.write(log)
        file.flush()
        return server_errors(Path(file.name))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sessions", type=int, default=20)
    parser.add_argument("--rounds", type=int, default=10)
    args = parser.parse_args()
    from playwright.sync_api import sync_playwright

    port = free_port()
    with tempfile.TemporaryDirectory() as tmp, sync_playwright() as playwright:
        process = serve(
            panel_serve("app", port),
            Path(tmp) / "server.log",
        )
        try:
            base = f"http://127.0.0.1:{port}/app"
            wait_until_served(base, process)
            time.sleep(2)
            idle = rss_mb(process.pid)
            browser = playwright.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
            start = time.perf_counter()
            pages = [open_page(browser, base, viewport=(1200, 800)) for _ in range(args.sessions)]
            opened = time.perf_counter() - start
            with_sessions = rss_mb(process.pid)
            cpu_before = cpu_seconds(process.pid)
            latencies, rounds = [], []
            for r in range(args.rounds):
                name = ("eps", "mu", "tau_ratio")[r % 3]
                key = "ArrowRight" if (r // 3) % 2 == 0 else "ArrowLeft"
                start = time.perf_counter()
                for _, page, _ in pages:
                    start_slider_move(page, name, key)
                done = [finish_slider_move(page) for _, page, _ in pages]
                rounds.append(time.perf_counter() - start)
                if min(done) < 0:
                    raise RuntimeError(f"round {r}: a page did not update")
                latencies.extend(done)
                time.sleep(0.5)
            cpu = cpu_seconds(process.pid) - cpu_before
            after = rss_mb(process.pid)
            errors = [e for _, _, errs in pages for e in errs]
            for context, _, _ in pages:
                context.close()
            browser.close()
            log = (Path(tmp) / "server.log").read_text()
        finally:
            process.terminate()
            process.wait(timeout=30)
    moves = args.sessions * args.rounds
    ordered = sorted(latencies)
    print(f"{args.sessions} sessions, {args.rounds} rounds of one slider move in every session")
    print(
        f"  server memory (RSS): idle {idle:.0f} MB, with sessions {with_sessions:.0f} MB "
        f"({(with_sessions - idle) / args.sessions:.1f} MB/session), after rounds {after:.0f} MB"
    )
    print(f"  opening the {args.sessions} sessions one after another: {opened:.1f} s")
    print(f"  server CPU: {cpu:.2f} s for {moves} moves = {1000 * cpu / moves:.1f} ms per move")
    print(
        f"  per-page latency (ms): median {statistics.median(latencies):.0f}, "
        f"p90 {ordered[int(0.9 * (len(ordered) - 1))]:.0f}, max {ordered[-1]:.0f}"
    )
    print(
        f"  round (all {args.sessions} updated) wall time: median "
        f"{statistics.median(rounds):.2f} s, max {max(rounds):.2f} s"
    )
    print(f"  console errors: {len(errors)}; server tracebacks: {log.count('Traceback')}")
    for entry in server_errors_in(log):
        print("  server:", " | ".join(entry.strip().splitlines()[:2]), "...", entry.strip()[-200:])


if __name__ == "__main__":
    main()
