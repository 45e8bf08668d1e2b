"""Scene 1, the drop: both balls from release to the second apex, and an animation of them."""

from __future__ import annotations

import holoviews as hv
import numpy as np
import panel as pn
import param

import twoball

from .scene import Scene
from .units import units_named

FRAMES = 240
LOWER, UPPER = "#1f77b4", "#d62728"


class DropScene(Scene):
    """Heights against time to the second apex, apexes marked, drop height and ICM as lines."""

    frame = param.Integer(default=0, bounds=(0, FRAMES - 1), doc="Animation frame.")

    def __init__(self, **params):
        super().__init__(**params)
        self.result: twoball.Result | None = None
        self.player = pn.widgets.Player(
            name="Animation",
            start=0,
            end=FRAMES - 1,
            value=0,
            interval=40,
            loop_policy="once",
            show_loop_controls=False,
            width=420,
        )
        self.player.link(self, value="frame")
        self.summary = pn.pane.Markdown(
            pn.bind(self._summary_text, self.param.revision), sizing_mode="stretch_width"
        )
        self.heights = (
            hv.DynamicMap(pn.bind(self._heights, self.param.revision))
            * hv.DynamicMap(pn.bind(self._cursor, self.param.frame, self.param.revision))
        ).opts(
            responsive=True,
            height=400,
            framewise=True,
            title="Heights from release to the second apex",
            legend_position="right",
        )
        self.balls = hv.DynamicMap(pn.bind(self._balls, self.param.frame, self.param.revision))

    def update(self) -> None:
        s = self.state
        self.result = twoball.simulate(
            s.eps, s.mu, s.tau_ratio, eps12=s.eps12, height=s.height, until="second", dense=True
        )

    def _summary_text(self, revision: int) -> str:
        if not self.active:
            return ""  # off screen: nothing is computed
        self.current()
        r, units = self.result, units_named(self.state.units)
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

    def _frame_time(self, frame: int) -> float:
        return self.result.end_time * frame / (FRAMES - 1)

    def _heights(self, revision: int) -> hv.Overlay:
        self.current()
        units = units_named(self.state.units)
        tr = self.result.trajectory
        t, scale = tr.t * units.time, units.length
        dims = dict(
            kdims=[hv.Dimension("t", label=units.time_label)],
            vdims=[hv.Dimension("X", label=units.length_label)],
        )
        apex_t = np.array(self.result.apex_t) * units.time
        apex_h = np.array(self.result.apex_h) * scale
        plane = [*dims["kdims"], *dims["vdims"]]
        labels = [f"h{i + 1} = {units.height(h)}" for i, h in enumerate(self.result.apex_h)]
        top = self._top() * scale
        return (
            hv.Curve((t, tr.x1 * scale), label="lower ball", **dims).opts(color=LOWER)
            * hv.Curve((t, tr.x2 * scale), label="upper ball", **dims).opts(color=UPPER)
            * hv.HLine(self.result.x2_0 * scale, label="drop height").opts(
                color="gray", line_dash="dashed"
            )
            * hv.HLine(self.result.h_icm * scale, label="ICM").opts(
                color="green", line_dash="dotted"
            )
            * hv.Points((apex_t, apex_h), kdims=plane).opts(color=UPPER, size=8)
            * hv.Labels((apex_t, apex_h, labels), kdims=plane, vdims="text").opts(
                text_font_size="10pt",
                yoffset=0.04 * float(apex_h.max(initial=1.0)),
                text_color=UPPER,
            )
            # invisible: keeps the apex labels and the ICM line inside the frame
            * hv.Scatter([(0.0, -0.03 * top), (1.08 * t[-1], 1.15 * top)], **dims).opts(alpha=0.0)
        )

    def _top(self) -> float:
        """The highest thing drawn: drop height, apexes or the ICM apex."""
        return max(self.result.x2_0, *self.result.apex_h, self.result.h_icm)

    def _cursor(self, frame: int, revision: int) -> hv.VLine:
        self.current()
        return hv.VLine(self._frame_time(frame) * units_named(self.state.units).time).opts(
            color="black", line_width=1
        )

    def _balls(self, frame: int, revision: int) -> hv.Points:
        self.current()
        units = units_named(self.state.units)
        tr = self.result.trajectory
        at = self._frame_time(frame)
        heights = np.array([np.interp(at, tr.t, tr.x1), np.interp(at, tr.t, tr.x2)]) * units.length
        top = self._top() * units.length
        return hv.Points(
            {"side": [-0.4, 0.4], "X": heights, "ball": ["lower", "upper"], "size": [26, 12]},
            kdims=["side", "X"],
            vdims=["ball", "size"],
        ).opts(
            color="ball",
            cmap={"lower": LOWER, "upper": UPPER},
            size="size",
            xlim=(-1, 1),
            ylim=(-0.03 * top, 1.08 * top),
            width=200,
            height=380,
            xaxis=None,
            ylabel=units.length_label,
            title=f"t = {at * units.time:.4g}",
            framewise=True,
            show_legend=False,
        )

    def __panel__(self) -> pn.viewable.Viewable:
        return pn.Column(
            self.summary,
            pn.Row(
                pn.pane.HoloViews(self.heights, sizing_mode="stretch_width", linked_axes=False),
                pn.pane.HoloViews(self.balls, linked_axes=False),
                sizing_mode="stretch_width",
            ),
            self.player,
            sizing_mode="stretch_width",
        )
