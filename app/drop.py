"""Scene 1, the drop: both balls from release to the second apex, and an animation of them.

Drawn with Bokeh directly: a slider move replaces the data of a few ColumnDataSources, which
is what makes the update fast (HoloViews' DynamicMap update cost about 240 ms a move here,
see benchmarks/app_latency.py). The run is asked for until the second apex only.
"""

from __future__ import annotations

import numpy as np
import panel as pn
import param
from bokeh.models import ColumnDataSource, LabelSet, Legend, LegendItem, Range1d, Span
from bokeh.plotting import figure

import twoball
from twoball.units import units_named

from .scene import Scene

FRAMES = 240
LOWER, UPPER = "#1f77b4", "#d62728"


class DropScene(Scene):
    """Heights against time to the second apex, apexes marked, drop height and ICM as lines."""

    frame = param.Integer(default=0, bounds=(0, FRAMES - 1), doc="Animation frame.")

    def __init__(self, **params):
        super().__init__(**params)
        self.result: twoball.Result | None = None
        self.player = pn.widgets.Player(
            label="Animation",
            start=0,
            end=FRAMES - 1,
            value=0,
            interval=40,
            loop_policy="once",
            show_loop_controls=False,
            sizing_mode="stretch_width",
            max_width=420,
        )
        self.player.link(self, value="frame")
        self.summary = pn.pane.Markdown(sizing_mode="stretch_width")
        self.curves = ColumnDataSource({"t": [], "x1": [], "x2": []})
        self.apexes = ColumnDataSource({"t": [], "h": [], "text": []})
        self.balls = ColumnDataSource(
            {"side": [-0.4, 0.4], "x": [0.0, 0.0], "size": [26, 12], "color": [LOWER, UPPER]}
        )
        self.drop_line = Span(dimension="width", line_color="gray", line_dash="dashed")
        self.icm_line = Span(
            dimension="width", line_color="green", line_dash="dotted", line_width=2
        )
        self.cursor = Span(dimension="height", location=0.0, line_color="black", line_width=1)
        self.heights = self._heights_figure()
        self.animation = self._animation_figure()
        self.param.watch(self._show_frame, "frame")
        self.param.watch(self._draw, "revision")

    def _heights_figure(self):
        fig = figure(
            height=400,
            sizing_mode="stretch_width",
            title="Heights from release to the second apex",
            y_range=Range1d(0.0, 1.0),  # set with every drop (auto-ranging ignores the lines)
            tools="pan,box_zoom,wheel_zoom,reset,save",
        )
        fig.toolbar.autohide = True
        lower = fig.line("t", "x1", source=self.curves, color=LOWER, line_width=2)
        upper = fig.line("t", "x2", source=self.curves, color=UPPER, line_width=2)
        fig.scatter("t", "h", source=self.apexes, color=UPPER, size=8)
        fig.add_layout(
            LabelSet(
                x="t",
                y="h",
                text="text",
                source=self.apexes,
                text_color=UPPER,
                text_font_size="10pt",
                x_offset=-50,
                y_offset=6,
            )
        )
        for span in (self.drop_line, self.icm_line, self.cursor):
            fig.add_layout(span)
        fig.add_layout(
            Legend(
                items=[
                    LegendItem(label="lower ball", renderers=[lower]),
                    LegendItem(label="upper ball", renderers=[upper]),
                ],
                location="top_left",  # inside: a phone has no width to spare
                background_fill_alpha=0.7,
            ),
        )
        return fig

    def _animation_figure(self):
        fig = figure(
            width=160,
            height=400,
            x_range=(-1, 1),
            y_range=Range1d(0.0, 1.0),
            tools="",
            toolbar_location=None,
            title="t = 0",
        )
        fig.scatter("side", "x", size="size", source=self.balls, color="color")
        fig.xaxis.visible = False
        return fig

    def update(self) -> None:
        s = self.state
        self.result = twoball.simulate(
            s.eps, s.mu, s.tau_ratio, eps12=s.eps12, height=s.height, until="second",
            dense_output=True,
            throw=False,  # a drop the solver cannot finish is shown as far as it got, with why
        )  # fmt: skip
        self.summary.object = self._summary_text()

    def _draw(self, *events: param.parameterized.Event) -> None:
        """Send the current drop to the figures (only while on screen)."""
        if not self.active:
            return
        self.current()
        r, units = self.result, units_named(self.state.units)
        tr = r.trajectory
        self.curves.data = {
            "t": tr.t * units.time,
            "x1": tr.x1 * units.length,
            "x2": tr.x2 * units.length,
        }
        self.apexes.data = {
            "t": np.array(r.apex_t) * units.time,
            "h": np.array(r.apex_h) * units.length,
            "text": [f"h{i + 1} = {units.height(h)}" for i, h in enumerate(r.apex_h)],
        }
        self.drop_line.location = r.x2_0 * units.length
        self.icm_line.location = r.h_icm * units.length
        top = max(r.x2_0, *r.apex_h, r.h_icm) * units.length
        for fig in (self.heights, self.animation):
            low, high = -0.03 * top, 1.12 * top
            fig.y_range.update(start=low, end=high, reset_start=low, reset_end=high)
        for fig in (self.heights, self.animation):
            fig.yaxis.axis_label = units.length_label
        self.heights.xaxis.axis_label = units.time_label
        self._show_frame()

    def _show_frame(self, *events: param.parameterized.Event) -> None:
        if self.result is None:
            return
        units = units_named(self.state.units)
        tr = self.result.trajectory
        at = self.result.end_time * self.frame / (FRAMES - 1)
        heights = [
            np.interp(at, tr.t, tr.x1) * units.length,
            np.interp(at, tr.t, tr.x2) * units.length,
        ]
        self.balls.patch({"x": [(slice(0, 2), heights)]})
        self.cursor.location = at * units.time
        self.animation.title.text = f"t = {at * units.time:.4g}"

    def _summary_text(self) -> str:
        r, units = self.result, units_named(self.state.units)
        if not r.success:
            return (
                f"**The solver could not finish this drop** ({r.reason}); what it computed is "
                "drawn. This is one of its known limits (docs/model.md): move a slider a little."
            )
        if r.h2 is None:
            second = f"no second bounce ({r.reason})"
            verdict = ""
        else:
            second = f"h2 = {units.height(r.h2)}, h2/h1 = {r.h2_over_h1:.4f}"
            verdict = "**delayed rebound** (h2 > h1)" if r.delayed_rebound else "no delayed rebound"
        first = "no first bounce" if r.h1 is None else f"h1 = {units.height(r.h1)}"
        return (
            f"{first}, {second}; {verdict}  \n"
            f"ICM apex (dotted green): {units.height(r.h_icm)}; drop height (dashed): "
            f"{units.height(r.x2_0)}; ball contacts in the first bounce: {r.contacts_first}"
        )

    def __panel__(self) -> pn.viewable.Viewable:
        self._draw()
        return pn.Column(
            self.summary,
            pn.Row(
                pn.pane.Bokeh(self.heights, sizing_mode="stretch_width"),
                pn.pane.Bokeh(self.animation),
                sizing_mode="stretch_width",
            ),
            self.player,
            sizing_mode="stretch_width",
        )
