"""Benchmark: from a slider move to updated plots in the browser (target: median
under 250 ms on the 2-core development machine).

Serves the app (``panel serve app``) and, as a baseline in the same run, a minimal Panel app
whose slider only replaces a 10-point line: the floor of the Panel/Bokeh round trip here.
In headless Chromium a slider handle gets a key press; the time runs until the plotted data
(every ColumnDataSource of the page) has changed and the next frame is painted. Moves are
spaced 500 ms apart (so the URL rewrite, 300 ms after a burst, is not inside a measurement).

    .venv/bin/python benchmarks/app_latency.py [--moves 45] [--scene drop|closeup|map]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tools"))

from appdriver import (  # noqa: E402
    CHROMIUM,
    CHROMIUM_ARGS,
    free_port,
    open_page,
    panel_serve,
    press_slider,
    serve,
    wait_until_served,
)

SLIDERS = ("eps", "mu", "tau_ratio")
BASELINE_APP = """
import numpy as np
import panel as pn
from bokeh.models import ColumnDataSource
from bokeh.plotting import figure

source = ColumnDataSource({"x": np.arange(10.0), "y": np.zeros(10)})
plot = figure(height=300)
plot.line("x", "y", source=source)
sliders = [pn.widgets.FloatSlider(start=0, end=1, step=0.01) for _ in range(3)]
for index, slider in enumerate(sliders):
    slider.param.watch(
        lambda event, index=index: setattr(
            source, "data", {"x": np.arange(10.0), "y": np.arange(10.0) * event.new + index}
        ),
        "value_throttled",
    )
pn.Row(pn.Column(*sliders), plot).servable()
"""


def measure(browser, url: str, moves: int, sliders: tuple[str, ...]) -> list[float]:
    context, page, errors = open_page(browser, url)
    try:
        times = []
        for i in range(moves):
            name = sliders[i % len(sliders)]
            key = "ArrowRight" if (i // len(sliders)) % 2 == 0 else "ArrowLeft"
            elapsed = press_slider(page, name, key)
            if elapsed < 0:
                raise RuntimeError(f"moving {name} did not update the plots")
            times.append(elapsed)
            page.wait_for_timeout(500)
        if errors:
            raise RuntimeError(f"console errors: {errors}")
        return times
    finally:
        context.close()


def served(command: list[str], path: str, port: int, log: Path):
    process = serve(command, log)
    wait_until_served(f"http://127.0.0.1:{port}/{path}", process)
    return process


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--moves", type=int, default=45)
    parser.add_argument("--scene", default="drop", choices=("drop", "closeup", "map"))
    args = parser.parse_args()
    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory() as tmp, sync_playwright() as playwright:
        baseline_file = Path(tmp) / "baseline.py"
        baseline_file.write_text(BASELINE_APP)
        browser = playwright.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
        results = {}
        for label, target, path in (
            ("baseline (10-point line)", str(baseline_file), "baseline"),
            (f"explorer, {args.scene} scene", "app", "app"),
        ):
            port = free_port()
            process = served(
                panel_serve(target, port),
                path,
                port,
                Path(tmp) / f"{path}.log",
            )
            try:
                query = f"?scene={args.scene}" if path == "app" else ""
                url = f"http://127.0.0.1:{port}/{path}{query}"
                # on the map, one eps step stays on the same cube slice: nothing to redraw
                sliders = ("mu", "tau_ratio") if args.scene == "map" else SLIDERS
                results[label] = measure(browser, url, args.moves, sliders)
            finally:
                process.terminate()
                process.wait(timeout=30)
        browser.close()
    base = statistics.median(results["baseline (10-point line)"])
    print(f"slider move -> updated plots in Chromium, {args.moves} moves each (ms)")
    for label, times in results.items():
        ordered = sorted(times)
        median = statistics.median(times)
        p90 = ordered[int(0.9 * (len(ordered) - 1))]
        print(
            f"  {label:26s} median {median:6.1f}  p90 {p90:6.1f}  max {ordered[-1]:6.1f}"
            f"  ratio to baseline {median / base:4.2f}"
        )
    median = statistics.median(results[f"explorer, {args.scene} scene"])
    print(f"target median < 250 ms: {'met' if median < 250 else 'NOT met'} ({median:.0f} ms)")


if __name__ == "__main__":
    main()
