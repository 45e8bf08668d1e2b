"""Scene 1, the drop: both balls from release to the second apex, and an animation of them.

Drawn with Bokeh directly: a slider move replaces the data of a few ColumnDataSources, which
is what makes the update fast (HoloViews' DynamicMap update cost about 240 ms a move here,
see benchmarks/app_latency.py). The run is asked for until the second apex only.
"""

from __future__ import annotations

import io
from dataclasses import dataclass

import numpy as np
import panel as pn
import param
from bokeh.models import (
    BoxAnnotation,
    Circle,
    ColumnDataSource,
    LabelSet,
    Legend,
    LegendItem,
    Line,
    NumeralTickFormatter,
    Range1d,
    Scatter,
    Span,
)
from bokeh.plotting import figure

import twoball
from twoball import presets
from twoball.observables import BALLS
from twoball.units import units_named

from .animation import Animation, FramePlayer
from .collisions import collisions
from .controls import PhoneSliders, on_a_phone
from .scene import (
    PROJECTED_PLAYER_HEIGHT,
    Scene,
    Text,
    answers_pending,
    draw,
    later,
    on_screen,
    player_for_a_room,
    readable,
    wrapping_row,
)
from .steps import STEPS
from .worksheet import drop_csv

FLIGHT_FRAMES = 240  # evenly spread over the drop
# Plotted samples, evenly spread over the drop: a parabola drawn through them is off by under
# 0.01 px on a plot 1920 px wide; each contact adds 9 more, its ends and the apexes are exact.
# (The solver's own plotting grid, 2001 points and 17 a phase, made 57 kB to send a move.)
PLOTTED = 400
COLLISION_FRAMES = 90  # added through each collision: slow motion there
# ... and through all of them together at most: a two-ball drop's four collisions get 90 each;
# a stack's dozens share them (at 90 each an eight-ball stack had 5 368 frames, 3.5 minutes of
# play, and nothing visibly moved in its first 7 s)
SLOW_FRAMES = 360
MIN_COLLISION_FRAMES = 10
TRAILS = "trails (the path of each ball's top)"
# Okabe-Ito blue and vermillion: told apart with every common colour-vision deficiency
LOWER, UPPER = "#0072B2", "#D55E00"
BALL_RADIUS = 0.06  # of the plot's height: the lower ball as drawn
PLAYER_HELP = (
    "Press play (the triangle): each collision is shown in **slow motion**, marked (slow). The "
    "balls are drawn to the heights' scale, each on the one below it."
)


@dataclass(frozen=True)
class PinnedDrop:
    """A drop kept on the plot to compare the next ones with (dimensionless, shown in the
    units on screen)."""

    label: str
    result: twoball.Result
    plotted: twoball.Trajectory


def drop_label(eps: float, eps12: float | None, mu: float, tau_ratio: float, height: float) -> str:
    """A drop in words: its preset's name when it is one, else its parameters."""
    for preset in presets.PRESETS.values():
        same = (preset.eps, preset.eps12, preset.mu, preset.tau_ratio) == (
            eps, eps12, mu, tau_ratio
        )  # fmt: skip
        if same and height == presets.height_from_metres(presets.DEFAULT_DROP_METRES):
            return preset.label.lower()
    label = f"eps {eps:.3g}, mu {mu:.3g}, tau_d/tau_f {tau_ratio:.3g}, H {height:.3g}"
    return label if eps12 is None else f"{label}, eps12 {eps12:.3g}"


def underneath(fig, added: list) -> list:
    """``added``, renderers just drawn on ``fig``, moved under its others (drawn first)."""
    fig.renderers = [*added, *(r for r in fig.renderers if r not in added)]
    return added


def frame_times(
    end: float, contacts: list[twoball.ContactInterval]
) -> tuple[np.ndarray, np.ndarray]:
    """The times of the animation's frames, even in flight and dense through each collision
    (:data:`COLLISION_FRAMES` each, :data:`SLOW_FRAMES` shared by all at most), and which of
    them lie within a collision (slow motion, said so in the caption)."""
    groups = [group for group in collisions(contacts) if group[0].start < end]
    through_each = max(
        MIN_COLLISION_FRAMES, min(COLLISION_FRAMES, SLOW_FRAMES // len(groups or [0]))
    )
    windows = [(group[0].start, min(max(c.end for c in group), end)) for group in groups]
    times = np.unique(
        np.concatenate(
            [np.linspace(0.0, end, FLIGHT_FRAMES)]
            + [np.linspace(start, stop, through_each) for start, stop in windows]
        )
    )
    slow = np.zeros(times.size, dtype=bool)
    for start, stop in windows:
        slow |= (start <= times) & (times <= stop)
    return times, slow


def plotted_times(result: twoball.Result) -> np.ndarray:
    """Times at which the drop is plotted: :data:`PLOTTED` even ones, 9 through every contact
    (its start and end among them) and the apexes."""
    through = [np.linspace(c.start, min(c.end, result.end_time), 9) for c in result.contacts]
    times = np.concatenate([np.linspace(0.0, result.end_time, PLOTTED), *through, result.apex_t])
    return np.unique(times[times <= result.end_time])


def ball_radii(mu: float) -> tuple[float, float]:
    """Drawn radii (fractions of the plot's height) of balls of equal density: m ~ r^3."""
    return BALL_RADIUS, BALL_RADIUS * mu ** (1 / 3)


def legend_above(fig, items: list[LegendItem]) -> None:
    """A legend above the plot area, in a row under the title: inside, top left, it covered
    the curves' start whenever the release was the highest point (and a phone has no width to
    spare for a legend beside the plot)."""
    legend = Legend(
        items=items, orientation="horizontal", padding=0, margin=4, spacing=16, border_line_alpha=0
    )
    fig.add_layout(legend, "above")


APEX_LABEL_LIFT = 6  # px: an apex's label above its point


def apex_label_offsets(
    apexes: list[float], low: float, high: float, sizes: dict
) -> tuple[list[float], float]:
    """Each apex label's height above its point in px, and the top of the heights' range that
    holds them. A label stands left of its point, just above it; when the two apexes are close
    in height (a low eps), the lower one's label, left of the right-most point, ran into the
    higher one's label and point (a phone at eps = 0.3): it then goes above the higher one's
    label, and the range grows to hold it. ``sizes``: the plot area's height, a label's line
    and a point's radius (px)."""
    offsets = [float(APEX_LABEL_LIFT)] * len(apexes)
    if len(apexes) != 2:
        return offsets, high
    lower, higher = sorted(range(2), key=lambda i: apexes[i])
    frame, line, point = sizes["frame"], sizes["line"], sizes["point"]
    for _ in range(3):  # (a grown range brings the points closer: checked again)
        scale = frame / (high - low)
        gap = (apexes[higher] - apexes[lower]) * scale
        if gap - point - 2 >= APEX_LABEL_LIFT + line:  # under the higher point: apart
            offsets[lower] = float(APEX_LABEL_LIFT)
            return offsets, high
        offsets[lower] = gap + 2 * APEX_LABEL_LIFT + line  # above the higher one's label
        need = offsets[lower] - gap + line + 2  # px above the higher point
        if (high - apexes[higher]) * scale >= need:
            return offsets, high
        # (high - h) frame / (high - low) = need, solved for high
        high = (apexes[higher] - need * low / frame) / (1 - need / frame)
    return offsets, high


def height_axis(fig) -> None:
    """Heights on the y axis in grouped digits, no exponent (200,000, not 2.000e+5)."""
    fig.yaxis.formatter = NumeralTickFormatter(format="0,0.[0000]")


def balls_glyph() -> Circle:
    """The balls of an animation: circles of the radii in column ``r`` (in heights), centred
    at ``x``, ``y``, filled with the colours in ``color``."""
    return Circle(
        x="x", y="y", radius="r", radius_dimension="y", fill_color="color", line_color="black"
    )


def stage():
    """The animation's stage: a narrow figure with the floor (a grey band below height 0) and
    no axis. A picture of the balls, each drawn on the one below at the heights' scale; its
    numbers would have been the stack's heights, which differ from each ball's on the heights
    plot beside it by the balls below (a new user took them for wrong heights), and the
    heights plot gives the numbers."""
    fig = figure(
        width=220,
        height=400,
        x_range=(-1, 1),
        y_range=Range1d(0.0, 1.0),
        x_axis_type=None,
        y_axis_type=None,
        tools="",
        toolbar_location=None,
        title="t = 0",
    )
    fig.add_layout(BoxAnnotation(top=0.0, fill_color="gray", fill_alpha=0.5))
    return fig


# an apex below 0 is real (docs/model.md: 0 is where the upper ball just touches the lower one
# resting unsquashed on the floor); said so, it no longer reads as a missing bounce
BELOW_ZERO = (
    " (below 0: the top ball barely left the ball under it, which was still pressed into the floor)"
)


def below_zero(height: float | None) -> str:
    """Why an apex is negative, for a summary (empty for an apex at or above 0)."""
    return BELOW_ZERO if height is not None and height < 0 else ""


# the heights figure's own style in a wrapping row: at least 340 px beside the stage, which
# wraps below it only on a narrow screen (the pane's styles never reach the figure, whose
# 100 % width then always pushed the stage below it: on a laptop out of sight)
BESIDE_STYLES = {"flex": "1 1 340px", "min-width": "0"}


def heights_and_stage(heights, animation, presentation: bool) -> pn.viewable.Viewable:
    """A scene's heights figure with its animation's stage beside it: a row on a projector
    (wide: never wrapped), else a row that wraps the stage below on a phone."""
    heights.styles = BESIDE_STYLES
    panes = (pn.pane.Bokeh(heights, sizing_mode="stretch_width"), pn.pane.Bokeh(animation))
    if presentation:
        return pn.Row(*panes, sizing_mode="stretch_width")
    return wrapping_row(*panes, sizing_mode="stretch_width")


# Presentation mode (scene.py), 1280 x 720: under the header (80 px) and the tabs (60) a one-line
# summary (:meth:`DropScene._projected_text`, 40 px), the heights, the player (112) and the row
# of the trails box, Pin and Download (50): the heights get 345 px, their data area about 250 of
# them (the legend's row above it, the time axis below; at 370 px the main area ran 20 px under
# the screen's foot, a teacher's trial). With the three-line summary they had 290, 193 px of
# data (the summary and the header took the rest of the screen).
PROJECTOR_PLOT_HEIGHT = 345
# ... and under a lesson's revealed answer, which stands for the summary but is taller (a line
# of 30 px text, 70 px, and the step's aside if it has one, two lines more, above the tabs): the
# player stays on the screen
PROJECTOR_PLOT_UNDER_ANSWER = 315
PROJECTOR_PLOT_UNDER_ANSWER_AND_ASIDE = 265
# the drop's stage there, beside the heights and the player, as tall as both: 220 x 290 beside
# the heights alone, its balls were small for a room (the player's row, beside the trails box,
# left the width unused)
PROJECTOR_STAGE_WIDTH = 270
# the projected summary: one line, no paragraph margin under it (Panel's 20 px)
PROJECTED_SUMMARY_CSS = ":host p { margin-bottom: 0; }"


class DropScene(Scene):
    """Heights against time to the second apex, apexes marked, drop height and ICM as lines."""

    def __init__(self, **params):
        super().__init__(**params)
        self.result: twoball.Result | None = None
        self.balls = ColumnDataSource(
            {"x": [0.0, 0.0], "y": [0.0, 0.0], "r": [0.05, 0.02], "color": [LOWER, UPPER]}
        )
        self.trail = ColumnDataSource({"t": [], "top0": [], "top1": []})
        self.cursor = Span(dimension="height", location=0.0, line_color="black", line_width=1)
        self.times = np.zeros(1)
        self.slow = np.zeros(1, dtype=bool)  # (frames in slow motion: frame_times)
        self.plotted: twoball.Trajectory | None = None  # the drop at the plotted times
        # a group of one box: its words are the box's <label> and toggle it (Bokeh's
        # Checkbox draws them beside the box, where a click did nothing)
        self.trails = pn.widgets.CheckBoxGroup(options=[TRAILS], value=[])
        self.trails.param.watch(self._show_trails, "value")
        self.download = pn.widgets.FileDownload(  # written when clicked, not at every move
            callback=self._csv, filename="drop.csv", label="Download this drop (CSV)", embed=False
        )
        self.summary = Text(sizing_mode="stretch_width")
        # compare two drops (tennis against ping-pong): one pinned, drawn dashed under the next
        self.pinned: PinnedDrop | None = None
        self.pin = pn.widgets.Button(label="Pin this drop to compare")
        self.pin.on_click(lambda _: later(self._toggle_pin))
        self.pinned_curves = ColumnDataSource({"t": [], "x1": [], "x2": []})
        self._pinned_item: LegendItem | None = None  # (its lines are added at the first pin)
        self._trail_lines: list | None = None  # (added when trails are first asked for)
        self.curves = ColumnDataSource({"t": [], "x1": [], "x2": []})
        answers_pending(self.curves)
        self.apexes = ColumnDataSource({"t": [], "h": [], "text": [], "dy": []})
        self.drop_line = Span(dimension="width", line_color="gray", line_dash="dashed")
        self.icm_line = Span(
            dimension="width", line_color="green", line_dash="dotted", line_width=2
        )
        self.heights = self._heights_figure()
        self.animation = self._animation_figure()
        # played in the browser (app/animation.py)
        self.animated = Animation(self.balls, self.cursor, self.animation.title, self.trail)
        self.player = FramePlayer(
            self.animated, end=FLIGHT_FRAMES - 1, **player_for_a_room(self.state.presentation)
        )
        for fig in (self.heights, self.animation):
            readable(fig, self.state.presentation)
        if self.state.presentation:  # 1280x720: under the header, tabs and summary, the player
            self.summary.stylesheets = [*self.summary.stylesheets, PROJECTED_SUMMARY_CSS]
            self.animation.width = PROJECTOR_STAGE_WIDTH
            self._answer_replaces_summary()  # (and the plots' heights: _fit_projector)

    @param.depends("state.revealed", "state.step", watch=True)
    def _answer_replaces_summary(self) -> None:
        """On a projector, a lesson's revealed answer (a large line above the scene) stands in
        for the summary, whose numbers the plot's labels also give: with both, the player
        was pushed below a 720 px screen."""
        s = self.state
        self.summary.visible = not (s.presentation and s.step > 0 and s.revealed)
        if s.presentation:
            self._fit_projector()

    def _fit_projector(self) -> None:
        """The heights' and the stage's heights on a projector: under the one-line summary,
        or under a lesson's answer (:data:`PROJECTOR_PLOT_UNDER_ANSWER`)."""
        if self.summary.visible:
            height = PROJECTOR_PLOT_HEIGHT
        elif STEPS[self.state.step - 1].aside:  # (the summary is hidden in a lesson's step)
            height = PROJECTOR_PLOT_UNDER_ANSWER_AND_ASIDE
        else:
            height = PROJECTOR_PLOT_UNDER_ANSWER
        if self.heights.height != height:
            self.heights.height = height
            self.animation.height = height + PROJECTED_PLAYER_HEIGHT
            if self.active:  # (the apex labels' offsets depend on the plot's height)
                self.redraw_now()

    def _heights_figure(self):
        fig = figure(
            height=400,
            sizing_mode="stretch_width",
            # (on a projector the teacher says what it shows, and its 290 px go to the curves:
            # under a title and the legend's row they had 150)
            title=None if self.state.presentation else "Heights to the second apex",
            y_range=Range1d(0.0, 1.0),  # set with every drop (auto-ranging ignores the lines)
            tools="pan,box_zoom,wheel_zoom,reset,save",
        )
        fig.toolbar.autohide = True
        height_axis(fig)
        lower = draw(fig, Line(x="t", y="x1", line_color=LOWER, line_width=2), self.curves)
        upper = draw(fig, Line(x="t", y="x2", line_color=UPPER, line_width=2), self.curves)
        apexes = Scatter(x="t", y="h", size=8, fill_color=UPPER, line_color=UPPER)
        draw(fig, apexes, self.apexes)
        fig.add_layout(
            LabelSet(
                x="t",
                y="h",
                text="text",
                source=self.apexes,
                text_color=UPPER,
                text_font_size="10pt",
                text_align="right",  # left of the point: h2 is at the right edge of the plot
                x_offset=-4,
                y_offset="dy",  # (apex_label_offsets)
            )
        )
        for span in (self.drop_line, self.icm_line, self.cursor):
            fig.add_layout(span)
        items = [LegendItem(label="lower ball", renderers=[lower]),
                 LegendItem(label="upper ball", renderers=[upper])]  # fmt: skip
        if self.state.presentation:  # (the summary's line that names the lines is not shown)
            items += self._line_keys(fig)
        legend_above(fig, items)
        return fig

    def _line_keys(self, fig) -> list[LegendItem]:
        """Legend entries for the textbook's apex and the release height, drawn as those
        lines are, from a point that is not drawn: on a projector the summary's line that names
        them is left out, and nothing on the screen said what the dotted green and dashed grey
        lines were (a teacher's trial)."""
        nothing = ColumnDataSource({"t": [np.nan], "y": [np.nan]})  # (none: no key drawn)
        keys = []
        for span, label in ((self.icm_line, "textbook (ICM)"), (self.drop_line, "released at")):
            line = Line(
                x="t",
                y="y",
                line_color=span.line_color,
                line_dash=span.line_dash,
                line_width=span.line_width,
            )
            keys.append(LegendItem(label=label, renderers=[draw(fig, line, nothing)]))
        return keys

    def _animation_figure(self):
        """The two balls, one on the other, above the floor (a grey band below height 0)."""
        fig = stage()
        draw(fig, balls_glyph(), self.balls)
        return fig

    def update(self) -> None:
        s = self.state
        self.result = twoball.simulate(
            s.eps, s.mu, s.tau_ratio, eps12=s.eps12, height=s.height, until="second",
            dense_output=True,
            throw=False,  # a drop the solver cannot finish is shown as far as it got, with why
        )  # fmt: skip
        self.summary.object = self._summary_text()
        self.plotted = self.result.evaluate(plotted_times(self.result))
        self.times, self.slow = frame_times(self.result.end_time, self.result.contacts)
        self.player.end = len(self.times) - 1

    @param.depends("revision", watch=True)
    def _draw(self, *events: param.parameterized.Event) -> None:
        """Send the current drop to the figures (only while on screen)."""
        if not self.active:
            return
        self.current()
        r, units = self.result, units_named(self.state.units)
        tr = self.plotted
        self.curves.data = {
            "t": on_screen(tr.t * units.time),
            "x1": on_screen(tr.x1 * units.length),
            "x2": on_screen(tr.x2 * units.length),
        }
        self.drop_line.location = r.x2_0 * units.length
        self.icm_line.location = r.h_icm * units.length
        top = max(r.x2_0, *r.apex_h, r.h_icm) * units.length
        self._draw_pinned(units)
        if self.pinned is not None:
            # (the upper ball's highest point: its release or an apex)
            pinned = self.pinned.result
            top = max(top, max(pinned.x2_0, *pinned.apex_h) * units.length)
        # room above the highest apex for its label (larger on a projector)
        # and below 0 room for the deepest squash (a heavy upper ball, mu = 10, presses the
        # lower one into the floor by more than 3 % of the top, which had cut its bottom)
        deepest = min(0.0, float(np.min(tr.x1, initial=0.0)), float(np.min(tr.x2, initial=0.0)))
        deepest *= units.length
        low = min(-0.03 * top, 1.05 * deepest)
        high = (1.2 if self.state.presentation else 1.12) * top
        apexes = [h * units.length for h in r.apex_h]
        offsets, high = apex_label_offsets(apexes, low, high, self._label_sizes())
        self.apexes.data = {
            "t": np.array(r.apex_t) * units.time,
            "h": np.array(apexes),
            "text": [f"h{i + 1} = {units.height(h)}" for i, h in enumerate(r.apex_h)],
            "dy": offsets,
        }
        self.heights.y_range.update(start=low, end=high, reset_start=low, reset_end=high)
        # the balls, drawn on top of their heights, fit: radii are fractions f of the stage's
        # span, so the upper ball's top, high + 2 (f1 + f2) (room - low), is at most room (the
        # upper ball is 10^(1/3) = 2.2 times the lower one at mu = 10: it was cut at the top
        # when the room was made for two balls of the lower one's size)
        diameters = 2 * sum(ball_radii(self.state.mu))
        room = (high - diameters * low) / (1 - diameters)
        self.animation.y_range.update(start=low, end=room, reset_start=low, reset_end=room)
        self.heights.yaxis.axis_label = units.length_label
        self.heights.xaxis.axis_label = units.time_label
        self._animate(units)

    def _label_sizes(self) -> dict:
        """What :func:`apex_label_offsets` needs of the heights figure, in px: its plot area's
        height (under-estimated: the figure less its title, legend and x axis), a label's line
        and an apex point's radius (both larger on a projector: app/scene.readable)."""
        fig = self.heights
        labels = next(a for a in fig.center if isinstance(a, LabelSet))
        size = labels.text_font_size
        size = str(size.get("value") if isinstance(size, dict) else getattr(size, "value", size))
        points = next(r.glyph for r in fig.renderers if isinstance(r.glyph, Scatter))
        return {
            "frame": fig.height - 120,
            "line": float(size.removesuffix("pt")) * 4 / 3 * 1.2,
            "point": points.size / 2,
        }

    def _draw_pinned(self, units) -> None:
        pinned = self.pinned
        if pinned is not None:
            self._add_pinned_lines()
        if self._pinned_item is not None:
            self._pinned_item.visible = pinned is not None
        if pinned is None:
            if len(self.pinned_curves.data["t"]):
                self.pinned_curves.data = {"t": [], "x1": [], "x2": []}
            return
        self.pinned_curves.data = {
            "t": on_screen(pinned.plotted.t * units.time),
            "x1": on_screen(pinned.plotted.x1 * units.length),
            "x2": on_screen(pinned.plotted.x2 * units.length),
        }

    def _add_pinned_lines(self) -> None:
        """The pinned drop's dashed lines, under the current drop's, added at the first pin
        (a page that never pins does not pay for their Bokeh models)."""
        if self._pinned_item is not None:
            return
        fig = self.heights
        lines = underneath(fig, [
            draw(fig, Line(x="t", y=column, line_color=color, line_width=2, line_dash="dashed",
                           line_alpha=0.6), self.pinned_curves)
            for column, color in (("x1", LOWER), ("x2", UPPER))
        ])  # fmt: skip
        readable(fig, self.state.presentation)
        self._pinned_item = LegendItem(label="pinned drop", renderers=lines)
        legend = fig.legend[0]
        legend.items = [*legend.items, self._pinned_item]

    def _add_trail_lines(self) -> None:
        """The dotted trails of the animation, added when first asked for."""
        if self._trail_lines is not None:
            return
        fig = self.animation
        # behind the balls, where they pass (beside them, at x = -0.6 and 0.6, they read as
        # two more things on the stage): the upper ball's over the lower's, which is wider
        self._trail_lines = underneath(fig, [
            draw(fig, Line(x=0.0, y=column, line_color=color, line_width=width), self.trail)
            for column, color, width in (("top0", LOWER, 8), ("top1", UPPER, 3))
        ])  # fmt: skip
        self.animated.draw_trails_with(self._trail_lines)

    def _toggle_pin(self) -> None:
        """Pin the drop on screen (the next drops are drawn over it), or let it go."""
        if self.pinned is None:
            self.current()
            s = self.state
            label = drop_label(s.eps, s.eps12, s.mu, s.tau_ratio, s.height)
            self.pinned = PinnedDrop(label, self.result, self.plotted)
            self.pin.label = "Unpin the dashed drop"
        else:
            self.pinned = None
            self.pin.label = "Pin this drop to compare"
        self.summary.object = self._summary_text()
        self.redraw_now()

    def _animate(self, units) -> None:
        """The animation of this drop, played in the browser (app/animation.py): the lower
        ball stands on its height X1, the upper ball on the lower one when X2 = X1 (they
        overlap by the compression)."""
        r = self.result
        top = self.animation.y_range.end - self.animation.y_range.start
        r1, r2 = (top * f for f in ball_radii(self.state.mu))

        def centres(times: np.ndarray) -> list[np.ndarray]:
            at = r.evaluate(times)
            return [at.x1 * units.length + r1, at.x2 * units.length + 2 * r1 + r2]

        frame = min(self.player.value_throttled, self.times.size - 1)
        self.animated.show(
            self.times * units.time,
            [float(c[0]) for c in centres(self.times[frame : frame + 1])],
            lambda: centres(self.times),
            [r1, r2],
            [LOWER, UPPER],
            at=frame,
            unit="s" if units.time != 1.0 else "tau",
            slow=self.slow,
        )

    def _show_trails(self, event: param.parameterized.Event) -> None:
        """Trails on or off (drawn in the browser as the animation plays: app/animation.py)."""
        shown = bool(event.new)
        if shown:
            self._add_trail_lines()
        for line in self._trail_lines or []:
            line.visible = shown
        if shown:  # drawn from the frames, at once (a new user saw them only on play)
            self.animated.send_frames()
            self.animated.redraw()  # (frames already in the page after a play: drawn now)

    def _csv(self) -> io.StringIO:
        """The drop on screen for a worksheet (app/worksheet.py)."""
        self.current()
        units = units_named(self.state.units)
        return io.StringIO(drop_csv(self.result, self.plotted, units))

    def _summary_text(self) -> str:
        if self.state.presentation:
            return self._projected_text()
        text = self._drop_text(self.result)
        if self.pinned is not None:
            pinned = self._drop_text(self.pinned.result).split("  \n")[0]
            text = f"**Now:** {text}  \n**Pinned (dashed),** {self.pinned.label}: {pinned}"
        return text

    def _projected_text(self) -> str:
        """The summary on a projector: one line, the apexes and the verdict (the drop height
        and the ICM apex are the plot's dashed and dotted lines, which the teacher names; an
        apex below 0 is said so, the teacher says why), or with a pinned drop both ratios."""
        r = self.result
        if self.pinned is not None:
            pinned = self.pinned.result
            ratios = [
                "no h2" if drop.h2 is None else f"h2/h1 = {drop.h2_over_h1:.3g}"
                for drop in (r, pinned)
            ]
            return f"**Now:** {ratios[0]}; **pinned (dashed):** {ratios[1]}"
        if not r.success:
            return "**The solver could not finish this drop:** move a slider a little."
        units = units_named(self.state.units)

        def apex(name: str, height: float | None) -> str:
            if height is None:
                return f"no {name}"
            return f"{name} = {units.height(height)}" + (" (below 0)" if height < 0 else "")

        if r.h2 is None:
            return f"{apex('h1', r.h1)}, no second bounce"
        verdict = "**delayed rebound** (h2 > h1)" if r.delayed_rebound else "no delayed rebound"
        return f"{apex('h1', r.h1)}, {apex('h2', r.h2)}, h2/h1 = {r.h2_over_h1:.3g}: {verdict}"

    def _drop_text(self, r: twoball.Result) -> str:
        units = units_named(self.state.units)
        if not r.success:
            return (
                f"**The solver could not finish this drop** ({r.reason}); what it computed is "
                "drawn. This is one of its known limits (docs/model.md): move a slider a little."
            )
        if r.h2 is None:
            second = f"no second bounce ({r.reason})"
            verdict = ""
        else:
            second = f"h2 = {units.height(r.h2)}{below_zero(r.h2)}, h2/h1 = {r.h2_over_h1:.4f}"
            verdict = "**delayed rebound** (h2 > h1)" if r.delayed_rebound else "no delayed rebound"
        first = (
            "no first bounce" if r.h1 is None else f"h1 = {units.height(r.h1)}{below_zero(r.h1)}"
        )
        return (
            f"{first}, {second}; {verdict}  \n"
            f"ICM apex (dotted green): {units.height(r.h_icm)}; upper ball released at "
            f"(dashed): {units.height(r.x2_0)}; ball contacts in the first bounce: "
            f"{r.contacts_first[BALLS]}"
        )

    def layout(self) -> pn.viewable.Viewable:
        self._draw()
        if self.state.presentation:
            return self._projected_layout()
        if on_a_phone():  # the sliders right under the plot (controls.PhoneSliders)
            plots = [
                pn.pane.Bokeh(self.heights, sizing_mode="stretch_width"),
                PhoneSliders(state=self.state),
                pn.pane.Bokeh(self.animation),
            ]
        else:
            plots = [heights_and_stage(self.heights, self.animation, self.state.presentation)]
        return pn.Column(
            self.summary,
            *plots,
            # wraps: on a phone a row squeezed the player until its first buttons left the screen
            wrapping_row(
                self.player, self.trails, self.pin, self.download, sizing_mode="stretch_width"
            ),
            # (on a projector the teacher says it: the room sees the scene without scrolling)
            *(
                []
                if self.state.presentation
                else [pn.pane.Markdown(PLAYER_HELP, sizing_mode="stretch_width")]
            ),
            sizing_mode="stretch_width",
        )

    def _projected_layout(self) -> pn.viewable.Viewable:
        """On a projector: the stage beside the heights and the player (:meth:`_fit_projector`),
        the trails box, Pin and Download in a row below."""
        plots = pn.Column(
            pn.pane.Bokeh(self.heights, sizing_mode="stretch_width"),
            self.player,
            sizing_mode="stretch_width",
        )
        return pn.Column(
            self.summary,
            pn.Row(plots, pn.pane.Bokeh(self.animation), sizing_mode="stretch_width"),
            wrapping_row(self.trails, self.pin, self.download, sizing_mode="stretch_width"),
            sizing_mode="stretch_width",
        )
