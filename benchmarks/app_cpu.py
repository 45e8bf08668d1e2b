"""Benchmark: the server's CPU for one slider move, per scene, without a browser (a class
of 40 moving sliders at once costs the server 40 times this).

Builds the explorer's page in a Bokeh document, as ``panel serve`` does for a session, and
times a change of the state (what a slider move does on the server: the scene's solver run,
its figures' data, Panel's widgets following the state) plus the PATCH-DOC message Bokeh would
send, serialised. The baseline, in the same process, is a page whose move only replaces a
10-point line. Medians of ``--moves`` moves after two warm-up moves.

    .venv/bin/python benchmarks/app_cpu.py [--moves 40] [--scenes "stack (eps)" ...]
        [--balls 3] [--force linear|hertz]

``--balls`` and ``--force`` are the Stack scene's (its eps moved as
benchmarks/stack_force_latency.py moves it, over ten values: a Hertz eps is calibrated once per
process, and the first ten moves of each pay for it).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

import numpy as np  # noqa: E402
import panel as pn  # noqa: E402
from bokeh.document import Document  # noqa: E402
from bokeh.models import ColumnDataSource  # noqa: E402
from bokeh.plotting import figure  # noqa: E402
from bokeh.protocol import Protocol  # noqa: E402
from panel.io.state import set_curdoc  # noqa: E402

# scene: (parameter moved, the values it steps through)
MOVES = {
    "drop": ("mu", np.linspace(0.01, 0.2, 7)),
    "closeup": ("mu", np.linspace(0.01, 0.2, 7)),
    "map (star)": ("mu", np.linspace(0.01, 0.2, 7)),
    "map (eps slice)": ("eps", np.linspace(0.5, 0.95, 7)),
    "map hertz (eps slice)": ("eps", np.linspace(0.5, 0.95, 7)),
    "stack": ("stack_ratio", np.linspace(0.1, 0.5, 7)),
    "stack (eps)": ("stack_eps", np.round(0.3 + 0.7 * (0.3 + 0.06 * np.arange(10)), 2)),
}
# a scene's page query besides its name (the Hertz map: a slice of a shipped Hertz cube)
QUERIES = {"map hertz (eps slice)": {"map_force": "hertz"}}


def timed_moves(document: Document, move, count: int) -> tuple[list[float], int]:
    """Milliseconds per move (the change and its serialised patch), and the patch's bytes (the
    median over the moves: an eps move's outline, and with it its patch, differs by slice)."""
    events: list = []
    document.on_change(events.append)
    times, sizes = [], []
    for i in range(count + 2):
        events.clear()
        start = time.perf_counter()
        move(i)
        if not events:
            continue  # (the first value may be the state's own: no move)
        message = Protocol().create("PATCH-DOC", list(events))
        size = len(message.content_json) + sum(len(b.to_bytes()) for b in message._buffers)
        if i >= 2:
            times.append(1e3 * (time.perf_counter() - start))
            sizes.append(size)
    return times, round(statistics.median(sizes))


def scene_moves(scene: str, count: int, stack: dict[str, str]) -> tuple[list[float], int]:
    from app.explorer import Explorer

    document = Document()
    with set_curdoc(document):
        explorer = Explorer({"scene": scene.split()[0], **stack, **QUERIES.get(scene, {})})
        explorer.page().server_doc(document)
    name, values = MOVES[scene]

    def move(i: int) -> None:
        setattr(explorer.state, name, float(values[i % len(values)]))

    # (moved outside the document's context: with it current and no session, the scene's
    # pn.io.hold collected its changes and never handed them to on_change, and the patch
    # measured was the slider's alone)
    return timed_moves(document, move, count)


def baseline_moves(count: int) -> tuple[list[float], int]:
    document = Document()
    with set_curdoc(document):
        source = ColumnDataSource({"x": np.arange(10.0), "y": np.zeros(10)})
        fig = figure(height=300)
        fig.line("x", "y", source=source)
        slider = pn.widgets.FloatSlider(start=0, end=1, value=0)
        slider.param.watch(lambda e: source.data.update(y=np.full(10, e.new)), "value")
        pn.Column(slider, pn.pane.Bokeh(fig)).server_doc(document)

        def move(i: int) -> None:
            slider.value = (i % 7) / 7

        return timed_moves(document, move, count)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--moves", type=int, default=40)
    parser.add_argument("--scenes", nargs="*", default=list(MOVES), choices=list(MOVES))
    parser.add_argument("--balls", type=int, default=3, help="the Stack scene's")
    parser.add_argument("--force", default="linear", choices=["linear", "hertz"])
    args = parser.parse_args()
    pn.extension()
    from app.app_hooks import bokeh_as_served
    from twoball import warmup

    warmup.warm_up()  # compiled kernels, as a running server has them
    bokeh_as_served()  # and Bokeh set up as the server sets it up
    rows = [("baseline (10-point line)", *baseline_moves(args.moves))]
    stack = {"N": str(args.balls), "force": args.force}
    rows += [(scene, *scene_moves(scene, args.moves, stack)) for scene in args.scenes]
    print(f"server CPU per slider move and the patch sent, medians of {args.moves} (ms, bytes)")
    for label, times, size in rows:
        print(f"{label:26s} {statistics.median(times):7.1f} ms {size:9d} B")


if __name__ == "__main__":
    main()
