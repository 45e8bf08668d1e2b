"""Scene 2, the first collision close up: positions and both contact forces (the paper's
close-up figure), the number of ball contacts and when each starts and ends.

The run stops at the first apex, and the trajectory is sampled only over the collision.
Drawn with Bokeh directly, like the drop scene: a move replaces one ColumnDataSource's data
(through HoloViews' DynamicMaps a move took about 320 ms in the browser, see the README).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import panel as pn
import param
from bokeh.models import ColumnDataSource, LegendItem, Line, Span
from bokeh.plotting import figure

import twoball
from twoball.observables import BALLS, FLOOR
from twoball.units import units_named

from .collisions import collisions, shown_collisions
from .controls import PhoneSliders, on_a_phone
from .drop import LOWER, UPPER, legend_above
from .scene import Scene, Text, answers_pending, draw, on_screen, readable, wrapping_row


def plural(count: int, noun: str) -> str:
    """``count`` and ``noun``, with an s for any count but 1."""
    return f"{count} {noun}{'s' * (count != 1)}"


FROM_CONTACT = "from contact"  # the positions' axis: each ball's height from its contact
SAMPLES = 600  # over the collision, with every contact's start and end: ~2 px apart at 1366 px
MARGIN = 0.08  # of the collision's duration, shown before and after it


def collision_window(contacts: list[twoball.ContactInterval], end: float) -> tuple[float, float]:
    """The contacts shown (:func:`shown_collisions`) with margins, before the first apex."""
    collision = shown_collisions(contacts)
    start = collision[0].start
    stop = max(c.end for c in collision)
    pad = MARGIN * (stop - start)
    return max(start - pad, 0.0), min(stop + pad, end)


# presentation mode (scene.py): positions; each force half of it. Under them the summary's line
# and the contacts' table, a contact a column: within 1280 x 720 with 360 (with 400, and the
# table a contact a row, it ran 200 px below the screen)
PROJECTOR_PLOT_HEIGHT = 340
# beside the forces, each at least 380 px wide (a phone wraps them one above the other)
BESIDE_STYLES = {"flex": "1 1 380px", "min-width": "0"}


def markdown_row(cells: list[str]) -> str:
    """A row of a Markdown table."""
    return "| " + " | ".join(cells) + " |"


class CloseUpScene(Scene):
    """X1, X2, f01 and f12 through the first collision, contacts listed."""

    def __init__(self, **params):
        super().__init__(**params)
        self.result: twoball.Result | None = None
        self.table = Text(
            pn.bind(self._contacts_text, self.param.revision, self.param.active),
            sizing_mode="stretch_width",
        )
        self.samples = ColumnDataSource({"t": [], "x1": [], "x2": [], "f01": [], "f12": []})
        answers_pending(self.samples)
        self.positions = self._figure("Positions (negative: compressed)", 400)
        lower = draw(
            self.positions, Line(x="t", y="x1", line_color=LOWER, line_width=2), self.samples
        )
        upper = draw(
            self.positions, Line(x="t", y="x2", line_color=UPPER, line_width=2), self.samples
        )
        self.positions.add_layout(Span(dimension="width", location=0.0, line_color="gray"))
        items = [LegendItem(label="X1 lower ball", renderers=[lower]),
                 LegendItem(label="X2 upper ball", renderers=[upper])]  # fmt: skip
        legend_above(self.positions, items)  # (inside, it covered the curves' start)
        # f12 is of order mu times f01: each force gets its own axis
        self.floor_force = self._figure("Floor force f01", 200, x_range=self.positions.x_range)
        draw(self.floor_force, Line(x="t", y="f01", line_color="black", line_width=2), self.samples)
        self.ball_force = self._figure("Ball-ball force f12", 200, x_range=self.positions.x_range)
        draw(self.ball_force, Line(x="t", y="f12", line_color=UPPER, line_width=2), self.samples)
        for fig in (self.positions, self.floor_force, self.ball_force):
            readable(fig, self.state.presentation)
        if self.state.presentation:  # side by side within 720 px (layout), a shorter title
            # (a contact a column: many contacts scroll sideways inside the table's box)
            self.table.stylesheets = [*self.table.stylesheets, ":host { overflow-x: auto; }"]
            self.positions.title.text = "Positions (< 0: compressed)"
            self.positions.height = PROJECTOR_PLOT_HEIGHT
            self.floor_force.height = self.ball_force.height = PROJECTOR_PLOT_HEIGHT // 2

    def _figure(self, title: str, height: int, **shared):
        """A figure of the scene; ``x_range`` shares the time axis with the first one.

        Few ticks: a collision spans a few units of time, which Bokeh's six ticks split into
        eight labels that touched on a phone; a force plot, half as tall, had seven."""
        fig = figure(
            title=title,
            height=height,
            sizing_mode="stretch_width",
            tools="pan,box_zoom,wheel_zoom,reset,save",
            **shared,
        )
        fig.xaxis.ticker.desired_num_ticks = 4
        fig.yaxis.ticker.desired_num_ticks = 4 if height > 200 else 3
        return fig

    @param.depends("revision", watch=True)
    def _draw(self, *events: param.parameterized.Event) -> None:
        """Send the current collision to the figures (only while on screen)."""
        if not self.active:
            return
        self.current()
        units = units_named(self.state.units)
        tr = self.result.trajectory
        self.samples.data = {
            "t": on_screen(tr.t * units.time),
            "x1": on_screen(tr.x1 * units.length),
            "x2": on_screen(tr.x2 * units.length),
            "f01": on_screen(tr.f01 * units.force),
            "f12": on_screen(tr.f12 * units.force),
        }
        for fig in (self.positions, self.floor_force, self.ball_force):
            fig.xaxis.axis_label = units.time_label
        # each ball's own coordinate, 0 where it touches what is below it: a teacher read the
        # upper ball's -135 as a height above the floor (SCENE_REGISTRY's caption says more)
        self.positions.yaxis.axis_label = f"{units.length_label}, {FROM_CONTACT}"
        self.floor_force.yaxis.axis_label = f"f01 {units.force_label}"
        self.ball_force.yaxis.axis_label = f"f12 {units.force_label}"

    def update(self) -> None:
        s = self.state
        drop = dict(eps12=s.eps12, height=s.height, until="first", throw=False)
        first = twoball.simulate(s.eps, s.mu, s.tau_ratio, dense_output=True, **drop)
        start, stop = collision_window(first.contacts, first.end_time)
        times = np.union1d(
            np.linspace(start, stop, SAMPLES),
            [t for c in first.contacts for t in (c.start, c.end) if start <= t <= stop],
        )
        self.result = dataclasses.replace(first, trajectory=first.evaluate(times))

    def _contacts_text(self, revision: bool, active: bool) -> str:
        """The contacts before the first apex, which the summary counts, each in the table:
        those of the first collision (the plots' window) first, then any after it, under a row
        that says so. (The table had listed the first collision's alone: at a large gap that is
        the lower ball's floor bounce, and the summary's 5 ball contacts came after it.)"""
        if not self.active:
            return ""  # off screen: nothing is computed
        self.current()
        units = units_named(self.state.units)
        r = self.result
        collision = shown_collisions(r.contacts)
        floors, balls = r.contacts_first
        counted = f"**{plural(balls, 'ball contact')}** and {plural(floors, 'floor contact')}"
        later = [c for c in r.contacts if c not in collision]
        alone = len(collisions(collision)) == 1
        if later:
            shown = [sum(c.contact == kind for c in collision) for kind in (FLOOR, BALLS)]
            first = min(c.start for c in collision) * units.time
            last = max(c.end for c in collision) * units.time
            what = (
                "the first collision alone"
                if alone
                else "the collisions up to the balls' first contact"
            )
            intro = (
                f"{counted} before the first apex, all listed below. The plots show {what}, "
                f"t = {first:.6g} to {last:.6g} "
                f"({plural(shown[1], 'ball contact')}, {plural(shown[0], 'floor contact')}); "
                f"the table lists {len(later)} more after it."
            )
        else:
            where = "in the first collision" if alone else "up to the balls' first contact"
            intro = f"{counted} before the first apex, all {where}, shown above."
        # the times' unit in the columns' heads ("time [s]" gives "[s]"; dimensionless, tau)
        unit = "[s]" if "[s]" in units.time_label else "(tau)"
        numbers = {}  # each contact's number among those of its kind, in time order
        for kind in (BALLS, FLOOR):
            ordered = sorted((c for c in r.contacts if c.contact == kind), key=lambda c: c.start)
            numbers.update({id(c): i for i, c in enumerate(ordered, 1)})

        def cells(c: twoball.ContactInterval) -> list[str]:
            name = "ball" if c.contact == BALLS else "floor"
            start, end = c.start * units.time, c.end * units.time
            return [f"{name} {numbers[id(c)]}", f"{start:.6g}", f"{end:.6g}", f"{end - start:.4g}"]

        # the first collision's ball contacts, then its floor contacts (as the plots stack
        # them), then the later contacts in time order
        table = [cells(c) for kind in (BALLS, FLOOR) for c in collision if c.contact == kind]
        if later:
            table.append(["*after the collision shown:*", "", "", ""])
            table += [cells(c) for c in sorted(later, key=lambda c: c.start)]
        heads = ["contact", f"starts {unit}", f"ends {unit}", f"lasts {unit}"]
        if self.state.presentation:
            # a room's screen: a contact a column, under one line (as rows, under the plots,
            # the table ran 200 px below a 1280 x 720 screen, and the teacher scrolled)
            columns = [heads, *table]
            rows = [[column[i] for column in columns] for i in range(len(heads))]
            intro = f"{counted} before the first apex:"
        else:
            rows = [heads, *table]
        lines = [intro, "", markdown_row(rows[0]), markdown_row(["---"] * len(rows[0]))]
        return "\n".join(lines + [markdown_row(row) for row in rows[1:]])

    def layout(self) -> pn.viewable.Viewable:
        self._draw()  # (on screen already: Explorer.scene)
        panes = [
            pn.pane.Bokeh(fig, sizing_mode="stretch_width")
            for fig in (self.positions, self.floor_force, self.ball_force)
        ]
        if self.state.presentation:  # 1280x720 (scene.py): positions beside the two forces
            plots = pn.Row(panes[0], pn.Column(*panes[1:]), sizing_mode="stretch_width")
            return pn.Column(plots, self.table, sizing_mode="stretch_width")
        # beside them on a laptop too (stacked, the three plots ended 100 px below a 1366x768
        # window), wrapped one above the other on a phone
        self.positions.styles = BESIDE_STYLES
        forces = pn.Column(*panes[1:], styles=BESIDE_STYLES, sizing_mode="stretch_width")
        # on a phone the two-ball sliders right under the positions, the first plot, as on the
        # Drop: the sidebar's lay at the page's foot, and then under all three plots, 800 px
        # down, a moved slider changed no plot in sight (teachers' trials). A line of their own
        # in the row (a basis of 100 %): hidden at 768 px and wider (controls.PHONE_ONLY), the
        # positions stand beside the forces there, on a phone turned sideways too
        phone = []
        if on_a_phone():
            sliders = PhoneSliders(state=self.state).__panel__()
            sliders.styles = {"flex": "1 1 100%"}
            phone = [sliders]
        plots = wrapping_row(panes[0], *phone, forces, sizing_mode="stretch_width")
        return pn.Column(plots, self.table, sizing_mode="stretch_width")
