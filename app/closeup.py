"""Scene 2, the first collision close up: positions and both contact forces (the paper's
close-up figure), the number of ball contacts and when each starts and ends.

The run stops at the first apex, and the trajectory is sampled only over the collision.
"""

from __future__ import annotations

import holoviews as hv
import numpy as np
import panel as pn

import twoball

from .drop import LOWER, UPPER
from .scene import Scene
from .units import units_named

SAMPLES = 1500
MARGIN = 0.08  # of the collision's duration, shown before and after it


def collision_window(contacts: list[twoball.ContactInterval], end: float) -> tuple[float, float]:
    """From the first contact to the last one that ends before the first apex, with margins."""
    start = min(c.start for c in contacts)
    stop = max(c.end for c in contacts)
    pad = MARGIN * (stop - start)
    return max(start - pad, 0.0), min(stop + pad, end)


class CloseUpScene(Scene):
    """X1, X2, f01 and f12 through the first collision, contacts listed."""

    def __init__(self, **params):
        super().__init__(**params)
        self.result: twoball.Result | None = None
        self.table = pn.pane.Markdown(
            pn.bind(self._contacts_text, self.param.revision), sizing_mode="stretch_width"
        )
        self.positions = hv.DynamicMap(pn.bind(self._positions, self.param.revision)).opts(
            responsive=True,
            height=300,
            framewise=True,  # on the DynamicMap: the axes follow a change of units too
            title="First collision: positions (negative = compressed)",
            legend_position="top_left",
        )
        # f12 is of order mu times f01: each force gets its own axis
        self.floor_force = hv.DynamicMap(pn.bind(self._force, "f01", self.param.revision)).opts(
            responsive=True, height=200, framewise=True, title="Floor force f01", color="black"
        )
        self.ball_force = hv.DynamicMap(pn.bind(self._force, "f12", self.param.revision)).opts(
            responsive=True, height=200, framewise=True, title="Ball-ball force f12", color=UPPER
        )

    def update(self) -> None:
        s = self.state
        drop = dict(eps12=s.eps12, height=s.height, until="first")
        first = twoball.simulate(s.eps, s.mu, s.tau_ratio, **drop)
        start, stop = collision_window(first.contacts, first.end_time)
        times = np.union1d(
            np.linspace(start, stop, SAMPLES),
            [t for c in first.contacts for t in (c.start, c.end) if start <= t <= stop],
        )
        self.result = twoball.simulate(s.eps, s.mu, s.tau_ratio, dense=times, **drop)

    def _contacts_text(self, revision: int) -> str:
        if not self.active:
            return ""  # off screen: nothing is computed
        self.current()
        units = units_named(self.state.units)
        r = self.result
        ball = [c for c in r.contacts if c.contact == "ball"]
        floor = [c for c in r.contacts if c.contact == "floor"]
        lines = [
            f"**{r.contacts_first} ball contact{'s' * (r.contacts_first != 1)}** and "
            f"{r.floor_contacts_first} floor contact before the first apex.",
            "",
            "| contact | starts | ends | lasts |",
            "| --- | --- | --- | --- |",
        ]
        for name, intervals in (("ball", ball), ("floor", floor)):
            for i, c in enumerate(intervals, 1):
                lines.append(
                    f"| {name} {i} | {c.start * units.time:.6g} | {c.end * units.time:.6g} "
                    f"| {(c.end - c.start) * units.time:.4g} |"
                )
        return "\n".join(lines)

    def _positions(self, revision: int) -> hv.Overlay:
        self.current()
        units = units_named(self.state.units)
        tr = self.result.trajectory
        t = hv.Dimension("t", label=units.time_label)
        x = hv.Dimension("X", label=units.length_label)
        return (
            hv.Curve((tr.t * units.time, tr.x1 * units.length), t, x, label="X1 lower ball")
            * hv.Curve((tr.t * units.time, tr.x2 * units.length), t, x, label="X2 upper ball")
            * hv.HLine(0.0).opts(color="gray", line_width=1)
        ).opts(hv.opts.Curve(color=hv.Cycle([LOWER, UPPER]), framewise=True))

    def _force(self, name: str, revision: int) -> hv.Curve:
        self.current()
        units = units_named(self.state.units)
        tr = self.result.trajectory
        t = hv.Dimension("t", label=units.time_label)
        f = hv.Dimension(name, label=f"{name} {units.force_label}")
        return hv.Curve((tr.t * units.time, getattr(tr, name) * units.force), t, f)

    def __panel__(self) -> pn.viewable.Viewable:
        return pn.Column(
            pn.pane.HoloViews(self.positions, sizing_mode="stretch_width"),
            pn.pane.HoloViews(self.floor_force, sizing_mode="stretch_width"),
            pn.pane.HoloViews(self.ball_force, sizing_mode="stretch_width"),
            self.table,
            sizing_mode="stretch_width",
        )
