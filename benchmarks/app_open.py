"""Benchmark: the server's CPU to open a page, per scene, without a browser or a network.

Builds a session's page as ``panel serve`` does (the explorer from the URL query, its page
put into a fresh Bokeh document under one ``freeze``, as app/main.py does) and serialises the
document as the first message to the browser would carry it. The baseline, in the same process,
is a page with one slider and a 10-point line. Medians of ``--pages`` pages of each kind after
three warm-up pages, the kinds built in turn (one page of each a round); CPU time of the
process (``time.process_time``).

    .venv/bin/python benchmarks/app_open.py [--pages 10] [--scene drop closeup] [--profile drop]
        [--query map_force=hertz]

Bokeh is set up as the server sets it up (``app_hooks.bokeh_as_served``: its defaults cached per
class, no per-session diagnostics) unless ``--bokeh-as-shipped``.

``--baseline DIR``: the same pages of another checkout DIR (e.g. ``git worktree add DIR
5018baa``) built in a second process beside this tree's, a page in each in turn, so that the
machine's state falls on both alike; the median of the pages' ratios, this tree over DIR. On
this machine the same page's median swung by a third between runs minutes apart.

``--served --baseline DIR``: both trees served (``twoball serve --num-procs 1`` each), pages
opened on each in turn, ``--pages`` a block, and each block's server CPU (all threads, to the
nanosecond) over the following 8 s in which its sessions are discarded and collected: a
page's whole cost to the server, the ratio of each block's, and this tree's per page.

``--served``: the same pages opened one at a time from ``twoball serve --num-procs 1`` by a
protocol client (tools/bokehclient.py), the server's CPU per page read from /proc (after each
page, a second for its onload callbacks and the URL's rewrite), and the messages (PATCH-DOC) a
page got in that second.
"""

from __future__ import annotations

import argparse
import contextlib
import cProfile
import pstats
import statistics
import sys
import time
from pathlib import Path
from types import SimpleNamespace

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

import numpy as np  # noqa: E402
import panel as pn  # noqa: E402
from bokeh.document import Document  # noqa: E402
from bokeh.models import ColumnDataSource  # noqa: E402
from bokeh.plotting import figure  # noqa: E402
from bokeh.protocol import Protocol  # noqa: E402
from panel.io.state import set_curdoc  # noqa: E402

SCENES = ("drop", "closeup", "map", "accuracy", "stack")


def first_message_bytes(document: Document) -> int:
    """The document as its first message to the browser (PULL-DOC-REPLY), serialised: bytes."""
    message = Protocol().create("PULL-DOC-REPLY", "request", document)
    return len(message.content_json) + sum(len(b.to_bytes()) for b in message._buffers)


def close(document: Document) -> None:
    """Close the page as the server closes a session: the document destroyed (its models let go
    of it, as ``ServerSession.destroy`` does), then its destroy callbacks, each failure passed
    over as Panel's ``_on_session_destroyed`` does. Without the first, every page stayed alive
    through Panel's per-page style sheets (``state._stylesheets``, whose models point back at
    their document): the heap grew by 10 000 objects a page, and the collections of the
    oldest generation, which walk all of it, took 16-37 ms of each drop page after 40 pages
    (``gc.callbacks``); without the second, every page stayed registered with Panel (drop:
    130 ms after 20 pages). The server process does both (bokeh's ``ServerSession.destroy``)."""

    def session(event) -> None:  # the server session's change callback, which destroy removes
        pass

    document.on_change(session)
    document.destroy(session)
    context = SimpleNamespace(id=f"closed-{id(document)}", _document=document)
    for callback in list(document.session_destroyed_callbacks):
        with contextlib.suppress(Exception):
            callback(context)


def explorer_page(query: dict[str, str]) -> tuple[dict[str, float], int, int]:
    """Build one page: CPU ms of its parts, its model count, its document's JSON bytes."""
    from app.explorer import Explorer

    document = Document()
    parts: dict[str, float] = {}
    with set_curdoc(document):
        start = time.process_time()
        explorer = Explorer(query)
        page = explorer.page()
        parts["explorer"] = time.process_time() - start
        start = time.process_time()
        with document.models.freeze():
            page.server_doc(document)
        parts["models"] = time.process_time() - start
    start = time.process_time()
    size = first_message_bytes(document)
    parts["json"] = time.process_time() - start
    count = len(document.models)
    close(document)
    return {k: 1e3 * v for k, v in parts.items()}, count, size


def baseline_page(query: dict[str, str]) -> tuple[dict[str, float], int, int]:
    """The same for a minimal Panel page (one slider, one 10-point line)."""
    document = Document()
    with set_curdoc(document):
        start = time.process_time()
        source = ColumnDataSource({"x": np.arange(10.0), "y": np.zeros(10)})
        fig = figure(height=300)
        fig.line("x", "y", source=source)
        slider = pn.widgets.FloatSlider(start=0, end=1, value=0)
        page = pn.template.BootstrapTemplate(sidebar=[slider], main=[pn.pane.Bokeh(fig)])
        built = time.process_time() - start
        start = time.process_time()
        with document.models.freeze():
            page.server_doc(document)
        models = time.process_time() - start
    start = time.process_time()
    size = first_message_bytes(document)
    parts = {"explorer": built, "models": models, "json": time.process_time() - start}
    count = len(document.models)
    close(document)
    return {k: 1e3 * v for k, v in parts.items()}, count, size


def measure(build, query: dict[str, str], pages: int) -> tuple[dict[str, float], int, int]:
    for _ in range(3):
        build(query)
    return summary([build(query) for _ in range(pages)])


def summary(runs: list) -> tuple[dict[str, float], int, int]:
    """The medians of pages' parts and totals, the last page's model count and bytes."""
    parts = {k: statistics.median(r[0][k] for r in runs) for k in runs[0][0]}
    parts["total"] = statistics.median(sum(r[0].values()) for r in runs)
    return parts, runs[-1][1], runs[-1][2]


def measure_in_turn(kinds: list[tuple[str, object, dict]], pages: int) -> list[tuple]:
    """(label, parts, models, bytes) of each kind of page (label, build, query), the pages
    built in turn, one of each kind a round: a spell of a slower machine (this one's CPU time
    for the same page swung by a third within minutes) falls on every kind alike, where
    one kind after another put it on whichever kind was being built."""
    for _ in range(3):
        for _, build, query in kinds:
            build(query)
    runs: dict[str, list] = {label: [] for label, _, _ in kinds}
    for _ in range(pages):
        for label, build, query in kinds:
            runs[label].append(build(query))
    return [(label, *summary(runs[label])) for label, _, _ in kinds]


def served(scene: str, pages: int) -> tuple[list[float], list[int]]:
    """Server CPU (ms) of each of ``pages`` pages opened one after another, and the messages
    (PATCH-DOC) each page got after its document."""
    import asyncio
    import tempfile

    sys.path.insert(0, str(REPO / "benchmarks"))
    sys.path.insert(0, str(REPO / "tools"))
    import app_load
    from appdriver import cpu_seconds, free_port
    from bokehclient import PageClient

    async def run() -> tuple[list[float], list[int]]:
        port = free_port()
        log = Path(tempfile.mkdtemp()) / "server.log"
        process = app_load.start_server(app_load.twoball_serve(port, 1), port, log, 1, True)
        url = f"http://127.0.0.1:{port}/app?scene={scene}"
        costs, patches = [], []
        try:
            for index in range(pages + 2):  # (the first two: the process's first pages)
                start = cpu_seconds(process.pid)
                client = PageClient(url)
                await client.open()
                await asyncio.sleep(1.0)
                if index >= 2:
                    costs.append(1e3 * (cpu_seconds(process.pid) - start))
                    patches.append(len(client.patches))
                await client.close()
        finally:
            process.terminate()
            process.wait(timeout=30)
        return costs, patches

    return asyncio.run(run())


def paired(scenes: list[str], pages: int, baseline: Path, extra: list[str]) -> None:
    """Each scene's page built in turn by this tree and by ``baseline`` (a worker process each,
    ``--worker``), and the ratio of each pair of pages' CPU."""
    import subprocess

    def worker(tree: Path, scene: str) -> subprocess.Popen:
        command = [sys.executable, __file__, "--worker", str(tree), "--scene", scene]
        return subprocess.Popen(
            [*command, "--query", *extra], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
        )

    def page(process: subprocess.Popen) -> float:
        process.stdin.write("page\n")
        process.stdin.flush()
        return float(process.stdout.readline())

    for scene in scenes:
        ours, theirs = worker(REPO, scene), worker(baseline, scene)
        try:
            ours.stdout.readline(), theirs.stdout.readline()  # (each warmed up: "ready")
            pairs = [(page(ours), page(theirs)) for _ in range(pages)]
        finally:
            for process in (ours, theirs):
                process.stdin.close()
                process.wait(timeout=60)
        ratios = [a / b for a, b in pairs]
        print(
            f"{scene}: this tree {statistics.median(a for a, _ in pairs):.1f} ms, baseline "
            f"{statistics.median(b for _, b in pairs):.1f} ms (medians of {pages}); ratio of "
            f"pairs, median {statistics.median(ratios):.3f} "
            f"(quartiles {np.percentile(ratios, 25):.3f}-{np.percentile(ratios, 75):.3f})"
        )


def serve_pages(query: dict[str, str]) -> None:
    """A worker of :func:`paired`: builds a page (total CPU ms, printed) for each line read."""
    measure(explorer_page, query, 1)
    print("ready", flush=True)
    for _ in sys.stdin:
        parts, _, _ = explorer_page(query)
        print(sum(parts.values()), flush=True)


def served_paired(scene: str, pages: int, baseline: Path, blocks: int = 4) -> None:
    """Pages opened on this tree's server and the baseline's in turn (:func:`paired`, served)."""
    import asyncio
    import tempfile

    sys.path.insert(0, str(REPO / "benchmarks"))
    sys.path.insert(0, str(REPO / "tools"))
    from appdriver import free_port
    from bokehclient import PageClient
    from served_moves import served_from, thread_cpu_seconds

    async def run() -> list[tuple[float, float]]:
        servers = []
        try:
            for checkout in (None, baseline):
                port = free_port()
                log = Path(tempfile.mkdtemp()) / "server.log"
                servers.append((f"http://127.0.0.1:{port}/app?scene={scene}",
                                served_from(checkout, port, log)))  # fmt: skip
            costs = []
            for block in range(blocks + 1):  # (the first: each process's first pages)
                start = [thread_cpu_seconds(process.pid) for _, process in servers]
                for _ in range(pages):
                    for url, _ in servers:
                        client = PageClient(url)
                        await client.open()
                        await asyncio.sleep(0.5)  # (its onload callbacks, its URL's rewrite)
                        await client.close()
                await asyncio.sleep(8)  # (closed sessions discarded within 6 s, collected)
                spent = [
                    thread_cpu_seconds(p.pid) - s for (_, p), s in zip(servers, start, strict=True)
                ]
                if block:
                    costs.append((1e3 * spent[0] / pages, 1e3 * spent[1] / pages))
            return costs
        finally:
            for _, process in servers:
                process.terminate()
                process.wait(timeout=30)

    costs = asyncio.run(run())
    ratios = [ours / theirs for ours, theirs in costs]
    print(
        f"{scene}: served, server CPU a page (opened, loaded, closed, collected), this tree "
        f"{statistics.median(c[0] for c in costs):.0f} ms, baseline "
        f"{statistics.median(c[1] for c in costs):.0f} ms (medians of {blocks} blocks of "
        f"{pages}); ratio, median of blocks {statistics.median(ratios):.3f} "
        f"({min(ratios):.3f} to {max(ratios):.3f})"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pages", type=int, default=10)
    parser.add_argument("--scene", nargs="*", default=list(SCENES))
    parser.add_argument("--present", action="store_true", help="presentation mode (?present=1)")
    parser.add_argument(
        "--query", nargs="*", default=[], help="more of the URL query, as key=value"
    )
    parser.add_argument("--profile", help="profile the pages of this scene instead")
    parser.add_argument("--served", action="store_true", help="from twoball serve, one by one")
    parser.add_argument("--baseline", type=Path, help="another checkout, paired page by page")
    parser.add_argument("--worker", type=Path, help=argparse.SUPPRESS)  # (a tree: paired)
    parser.add_argument(
        "--bokeh-as-shipped",
        action="store_true",
        help="Bokeh as installed, not as the server sets it up (app_hooks.bokeh_as_served)",
    )
    args = parser.parse_args()
    if args.served and args.baseline:
        for scene in args.scene:
            served_paired(scene, args.pages, args.baseline)
        return
    if args.served:
        for scene in args.scene:
            costs, patches = served(scene, args.pages)
            print(
                f"{scene}: served, server CPU per page, median of {args.pages}: "
                f"{statistics.median(costs):.0f} ms (all: {', '.join(f'{c:.0f}' for c in costs)}); "
                f"messages after the document: {statistics.median(patches):.0f}"
            )
        return
    if args.baseline:
        paired(args.scene, args.pages, args.baseline, args.query)
        return
    if args.worker:  # (this tree's app, or the baseline's: paired)
        sys.path.insert(0, str(args.worker))
    pn.extension()
    from app.app_hooks import bokeh_as_served, exempt_the_server_from_collection
    from twoball import warmup

    if not args.bokeh_as_shipped:
        bokeh_as_served()  # as the server does (app/app_hooks.py)

    warmup.warm_up()  # compiled kernels, as a running server has them
    exempt_the_server_from_collection()  # as the server does after start-up
    extra = {"present": "1"} if args.present else {}
    extra.update(item.split("=", 1) for item in args.query)
    if args.worker:
        serve_pages({"scene": args.scene[0], **extra})
        return
    if args.profile:
        query = {"scene": args.profile, **extra}
        measure(explorer_page, query, 1)
        profile = cProfile.Profile()
        profile.runcall(lambda: [explorer_page(query) for _ in range(args.pages)])
        pstats.Stats(profile).sort_stats("cumulative").print_stats(40)
        return
    kinds = [("baseline (slider, line)", baseline_page, {})]
    kinds += [(scene, explorer_page, {"scene": scene, **extra}) for scene in args.scene]
    rows = measure_in_turn(kinds, args.pages)
    print(
        f"server CPU to open a page, median of {args.pages} built in turn (ms); models; "
        "document (bytes)"
    )
    heads = ("total", "build", "models", "json")
    print(f"{'page':26s} " + " ".join(f"{h:>7s}" for h in heads) + f" {'n':>5s} {'bytes':>8s}")
    for label, parts, count, size in rows:
        print(
            f"{label:26s} {parts['total']:7.1f} {parts['explorer']:7.1f} {parts['models']:7.1f} "
            f"{parts['json']:7.1f} {count:5d} {size:8d}"
        )


if __name__ == "__main__":
    main()
