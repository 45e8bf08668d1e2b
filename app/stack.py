"""The Stack scene: N balls dropped as one stack (the Astroblaster toy), the top ball's bounce
against the textbook chain of independent collisions (docs/model.md, "Stacks of N balls").

Drawn with Bokeh directly, like the drop scene. One mass ratio for every pair (each ball that
much lighter than the one below, as in the toy), one restitution and one gap: the library and
``twoball stack`` take a value per pair. Heights are dimensionless here whatever the units
chosen for the two-ball scenes (the presets are for a basketball and one ball on it).
"""

from __future__ import annotations

import math
from contextlib import nullcontext

import numpy as np
import panel as pn
import param
from bokeh.models import (
    ColumnDataSource,
    LabelSet,
    Legend,
    LegendItem,
    Line,
    Range1d,
    Scatter,
    Span,
)
from bokeh.plotting import figure

from twoball.errors import ParameterError
from twoball.stacks import StackResult, icm_chain, simulate_stack
from twoball.stacks.model import MASS_RATIO_RANGE
from twoball.units import number_text

from .animation import Animation, FramePlayer
from .controls import (
    ReleasedIntSlider,
    ReleasedSlider,
    announce_moves,
    on_a_phone,
    phone_only,
    plain,
)
from .drop import (
    balls_glyph,
    below_zero,
    frame_times,
    height_axis,
    heights_and_stage,
    stage,
    underneath,
)
from .scene import (
    PROJECTED_PLAYER_HEIGHT,
    Folded,
    Scene,
    Text,
    answers_pending,
    draw,
    on_screen,
    player_for_a_room,
    readable,
)
from .state import contact_eps

# Okabe-Ito: told apart with every common colour-vision deficiency, bottom ball first, up to
# eight balls; its bluish green left out, a grey (its usual eighth) in its place: a stack of
# three drew its top ball in it, next to the chain's dotted green line (ICM_COLOUR), and a
# class took the one for the other (a teacher's trial)
PALETTE = ("#0072B2", "#E69F00", "#CC79A7", "#D55E00", "#56B4E9", "#F0E442", "#999999", "#000000")
ICM_COLOUR = "green"  # the chain's line, "dotted green" as every scene and the lesson say
# The stage draws the stack at rest STACK_SHARE of its height tall, the bottom ball's radius at
# most BALL_RADIUS of it: eight balls, each with a radius of 0.05, had made the stage five
# times the heights' span, the stack 40 px tall on a projector with its top ball under a pixel.
BALL_RADIUS = 0.08  # the bottom ball, as a fraction of the stage's height, at most
STACK_SHARE = 0.45
SMALLEST_BALL = 0.2  # a ball's radius over the bottom ball's, at least: visible (a ball 1e-5
# as heavy has 0.02 of its radius at equal density)
SAMPLES = 400  # plotted times over the drop (as app/drop.py's PLOTTED), plus through contacts:
CONTACT_SAMPLES = 3600  # all contacts' together at most, 9 a contact at most, 2 at least (its
# start and end): an eight-ball stack's 2 500 contacts at 9 each were 23 000 times of 8 balls,
# a 740 kB patch that took a browser about 2 s to draw
CAPTION_HELP = (
    "Each ball is *ratio* times as heavy as the one below it. The dotted green line is the "
    "textbook chain of independent collisions (floor first, then each pair in turn): for three "
    "elastic balls with a very light top ball, 49 times the drop height. Press play: the "
    "animation slows down through each collision, and draws the balls stacked, each on those "
    "below it. The stack's sliders take the two-ball ones' place among the controls (the side "
    "panel; on a phone also right under the heights); it shares their drop height H (advanced). "
    "Heights here are always dimensionless."
)

# ... and on a projector, beside the player: below it the whole text ran off a 1280x720 screen
# (under the summary, plots and player only its first line was left). Shorter there (the
# summary names the dotted green line; the sliders' place and the dimensionless heights are the
# teacher's to say), in a box as tall as the player that scrolls if a screen draws it longer,
# never cut.
PROJECTED_CAPTION = (
    "Each ball is *ratio* times as heavy as the one below it; the animation slows down "
    "through each collision."
)
PROJECTED_CAPTION_CSS = ":host { overflow-y: auto; } :host p { margin: 0; }"


PROJECTOR_PLOT_HEIGHT = 300  # presentation mode (scene.py): plots and player in 720 px, with
# room to spare for a touch screen's taller buttons; the legend stands above the curves there,
# in one row (below them, at 310 px, it left the curves 115 px; right of them, a third of the
# plot's width)
APEX_COLUMNS = ("t", "h", "text", "align", "dx")  # each label's alignment and offset its own
# A stack the solver refuses (too light a top ball, too small a gap for five balls, a Hertz
# contact too damped at the explorer's H...): the summary says why, and the plots keep the last
# stack it carried, dimmed, named in the summary. Not sliders' ranges that exclude every refused
# stack: what is refused depends on N, the ratio, the gap, eps per contact, the force and H
# (a two-ball slider), together; ranges that moved with each other would also move a value the
# teacher set. (Emptied, the plots left a class looking at blank axes.) See :meth:`_dim`.


def ball_sizes(masses: np.ndarray) -> np.ndarray:
    """Each ball's radius on the stage, as a fraction of its height: as the cube root of its
    mass (equal density), at least :data:`SMALLEST_BALL` of the bottom ball's, the stack's
    diameters together :data:`STACK_SHARE` of the stage (the bottom ball's radius at most
    :data:`BALL_RADIUS`)."""
    sizes = np.maximum(np.asarray(masses, dtype=float) ** (1 / 3), SMALLEST_BALL)
    return sizes * min(BALL_RADIUS, STACK_SHARE / (2 * sizes.sum()))


def times_text(ratio: float) -> str:
    """A ratio to three significant figures, written out ("1,330 times", not "1.33e+03")."""
    return number_text(float(f"{ratio:.3g}"))


class StackScene(Scene):
    """Every ball's height to the top ball's second apex, the ICM chain, an animation."""

    watched = (
        "height",
        "balls",
        "stack_ratio",
        "stack_eps",
        "stack_gap",
        "force",
        "stack_eps_contacts",
        "units",  # (only the summary's note that this scene has none)
    )

    def __init__(self, **params):
        super().__init__(**params)
        self.result: StackResult | None = None  # the last stack the solver carried
        self.refused: str | None = None  # why it refused the stack asked for, if it did
        self._plots: list[pn.viewable.Viewable] = []  # dimmed when refused (:meth:`layout`)
        self._carried = ""  # the last stack carried, in words (for a refusal's message)
        self._run: tuple[tuple, dict] = ((), {})  # simulate_stack's arguments, options (update)
        self.times = np.zeros(1)
        self.slow = np.zeros(1, dtype=bool)  # (frames in slow motion: frame_times)
        state = self.state.param
        # in the sidebar, in place of the two-ball sliders (own_controls), one under the other
        self.widgets = pn.Column(
            *self._sliders(),
            # (no tooltip from the parameter's doc: to the buttons' right, a phone cut it off)
            pn.widgets.RadioButtonGroup.from_param(
                state.force, name="force", width=200, description=None
            ),
            sizing_mode="stretch_width",
        )
        # eps per contact, under "advanced" (collapsed: the one eps slider is the lesson's)
        self.eps_contacts = pn.widgets.TextInput.from_param(
            state.stack_eps_contacts,
            # (short: a longer title was cut in the sidebar; the placeholder and the message
            # of a wrong entry say the rest)
            name="eps per contact: floor, 1-2, 2-3, ...",
            placeholder="e.g. 0.9, 0.8, 0.7 (empty: the eps slider's)",
            sizing_mode="stretch_width",
        )
        self.eps_message = pn.pane.Alert(alert_type="warning", visible=False, margin=(0, 5))
        self.advanced = Folded(
            "advanced: eps per contact", lambda: [self.eps_contacts, self.eps_message]
        )
        self._controls = pn.Column(self.widgets, sizing_mode="stretch_width")
        self._controls.append(self.advanced.place(self._controls))
        self.summary = Text(sizing_mode="stretch_width")
        self.curves = ColumnDataSource({"t": []})
        self._lines: list = []  # a line per ball drawn so far (:meth:`_add_lines`)
        answers_pending(self.curves)
        self.apexes = ColumnDataSource({c: [] for c in APEX_COLUMNS})
        # a refusal changes no plotted data: this answers the change (the page's "pending")
        self.refusals = ColumnDataSource({"n": []})
        answers_pending(self.refusals)
        self.balls_drawn = ColumnDataSource({"x": [], "y": [], "r": [], "color": []})
        self.icm_line = Span(
            dimension="width", line_color=ICM_COLOUR, line_dash="dotted", line_width=2
        )
        self.cursor = Span(dimension="height", location=0.0, line_color="black", line_width=1)
        self.heights = self._heights_figure()
        self.animation = self._animation_figure()
        # played in the browser (app/animation.py)
        self.animated = Animation(self.balls_drawn, self.cursor, self.animation.title)
        self.player = FramePlayer(
            self.animated, end=1, **player_for_a_room(self.state.presentation)
        )
        for fig in (self.heights, self.animation):
            readable(fig, self.state.presentation)
        if self.state.presentation:  # plots and player within 720 px (scene.py)
            self.heights.height = self.animation.height = PROJECTOR_PLOT_HEIGHT

    def _sliders(self) -> list[pn.widgets.Widget]:
        """N, the mass ratio, eps and the gap, each linked both ways to the state (a set for the
        sidebar, and one under a phone's plots: :meth:`layout`); each recomputes the stack on
        release only (not at every step of a drag), and its release clears the URL's messages
        (the state's ``slider_moved``), as the two-ball sliders' does."""
        state = self.state.param
        ratio = "mass ratio" if self.state.presentation else "mass ratio (ball / ball below)"
        sliders = [
            ReleasedIntSlider.from_param(
                state.balls, name="balls N", throttled=True, sizing_mode="stretch_width"
            ),
            ReleasedSlider.from_param(
                state.stack_ratio,
                name=ratio,
                step=0.01,
                throttled=True,
                sizing_mode="stretch_width",
            ),
            ReleasedSlider.from_param(
                state.stack_eps, name="eps", step=0.01, throttled=True, sizing_mode="stretch_width"
            ),
            ReleasedSlider.from_param(
                state.stack_gap,
                name="gap tau_d/tau_f",
                step=0.05,
                throttled=True,
                sizing_mode="stretch_width",
            ),
        ]
        for slider in sliders:
            announce_moves(slider, self.state)
        return sliders

    def _heights_figure(self):
        fig = figure(
            height=400,
            sizing_mode="stretch_width",
            # (on a projector the teacher says what it shows, and the legend's row stands
            # there: under both, the stage beside had 157 px, its eight balls 60 px tall)
            title=None if self.state.presentation else "Heights to the top ball's h2",
            y_range=Range1d(0.0, 1.0),
            tools="pan,box_zoom,wheel_zoom,reset,save",
            # (the drop's dimensionless labels: a stack has no units to switch to)
            x_axis_label="time tau",
            y_axis_label="height X",
        )
        fig.toolbar.autohide = True
        height_axis(fig)
        draw(
            fig, Scatter(x="t", y="h", size=8, fill_color="black", line_color="black"), self.apexes
        )
        # h1 centred above its point (left of it, on a phone and on a projector, it ran over
        # the height axis' labels), h2 left of its point (it is at the plot's right edge)
        fig.add_layout(
            LabelSet(
                x="t", y="h", text="text", source=self.apexes, text_font_size="10pt",
                text_align="align", x_offset="dx", y_offset=8,
            )
        )  # fmt: skip
        # (six labels of 0 to 14000 ran into each other on a phone; a projector's are 4 too)
        fig.xaxis.ticker.desired_num_ticks = 4
        fig.add_layout(self.icm_line)
        fig.add_layout(self.cursor)
        # outside the curves (inside, eight balls' legend hid them and the apex labels): below
        # them, four a row; on a projector, whose height is what is short, one row above them,
        # "ball 1", then each number (right of them, "ball 1" to "ball 8" took a third of the
        # plot's width at 1280x720)
        if self.state.presentation:
            self.legend = Legend(
                items=[], orientation="horizontal", padding=0, margin=4, spacing=14,
                label_standoff=4, border_line_alpha=0,
            )  # fmt: skip
            fig.add_layout(self.legend, "above")
        else:
            self.legend = Legend(items=[], orientation="horizontal", ncols=4)
            fig.add_layout(self.legend, "below")
        return fig

    def _add_lines(self, balls: int) -> None:
        """A line and a legend entry for each of the first ``balls`` balls, under the apexes
        and labels: added when a stack of that many is first drawn (a page of three balls does
        not pay for eight)."""
        if balls <= len(self._lines):
            return
        # the document's model graph worked out once for all the new lines (each line and
        # legend item had the document walk its whole graph again: 12 times, 3 -> 8 balls,
        # most of that move's 190 ms)
        document = self.heights.document
        with document.models.freeze() if document is not None else nullcontext():
            for ball in range(len(self._lines), balls):
                glyph = Line(x="t", y=f"x{ball}", line_color=PALETTE[ball], line_width=2)
                self._lines.append(draw(self.heights, glyph, self.curves))
                label = f"{ball + 1}" if self.state.presentation and ball else f"ball {ball + 1}"
                item = LegendItem(label=label, renderers=[self._lines[-1]])
                self.legend.items = [*self.legend.items, item]
            underneath(self.heights, self._lines)  # (ball 1's drawn first, as before)
            readable(self.heights, self.state.presentation)

    def _animation_figure(self):
        fig = stage()
        draw(fig, balls_glyph(), self.balls_drawn)
        draw(fig, Scatter(x="n", y="n", size=0), self.refusals).visible = False  # (never drawn)
        return fig

    def contact_eps(self) -> list[float] | float:
        """The eps of each contact typed under "advanced", else the slider's for all; a bad
        entry shows its message and the slider's is used (the stack is still drawn)."""
        s = self.state
        values, message = contact_eps(s.stack_eps_contacts, s.balls)
        self.eps_message.object = "" if message is None else (
            f"**eps per contact:** {plain(message)}. Using eps = {s.stack_eps:g} for every contact."
        )  # fmt: skip
        self.eps_message.visible = message is not None
        if message is not None:  # opened: a wrong entry (from a link too) said where it is seen
            self.advanced.open()
        return s.stack_eps if values is None else values

    def update(self) -> None:
        s = self.state
        arguments = ([s.stack_ratio] * (s.balls - 1), self.contact_eps(), s.stack_gap)
        options = {"height": s.height, "force": s.force, "throw": False}
        try:
            # one run to the second apex, its dense output kept: sampled once its end is known
            result = simulate_stack(*arguments, **options, dense_output=True)
        except ParameterError as error:  # e.g. six balls, each 0.01 of the one below: 1e-10
            self.refused = self._refusal_text(str(error))
            self.summary.object = self.refused
            return
        self.refused = None
        self._run = (arguments, options)  # (the animation's frames are a run of their own)
        self.result = self._sampled(result)
        self._carried = f"{s.balls} balls with mass ratio {s.stack_ratio:g}"
        self.summary.object = self._summary_text()
        r = self.result
        self.times, self.slow = frame_times(r.end_time, r.contacts)  # the animation's
        self.player.end = len(self.times) - 1

    def _refusal_text(self, error: str) -> str:
        """What the summary says of a stack the solver refuses: why, what to change, and that
        the dimmed plots are the last stack it carried (why not sliders' ranges: above
        :func:`ball_sizes`; README says so too)."""
        s = self.state
        lightest = s.stack_ratio ** (s.balls - 1)
        if "mass_ratios" in error and lightest < MASS_RATIO_RANGE[0]:
            # in the class's words, not the library's (a teacher read "ball 0" and
            # "products of mass_ratios" in it; the legend counts balls from 1)
            low = MASS_RATIO_RANGE[0]
            fewest = 1 + math.floor(math.log(low) / math.log(s.stack_ratio))
            why = (
                f"with {s.balls} balls, each {s.stack_ratio:g} of the one below, the top ball is "
                f"{lightest:.1g} of the bottom one, and the solver carries masses down to {low:g} "
                f"of it. Choose a mass ratio of at least "
                f"{math.ceil(100 * low ** (1 / (s.balls - 1))) / 100:g}, "
                f"or at most {fewest} balls."
            )
        else:
            change = (
                "Choose fewer balls or a larger mass ratio."
                if "mass_ratios" in error
                else ("Change the value it names.")
            )
            why = f"{plain(error)}. {change}"
        text = f"**This stack is outside what the solver carries:** {why}"
        if self.result is None:  # (a page opened on it: nothing carried yet)
            return text
        return f"{text}  \n*Dimmed below: the last stack it carried, {self._carried}.*"

    @staticmethod
    def _sampled(result: StackResult) -> StackResult:
        """``result`` (a run to the top ball's second apex, with its dense output) with its
        heights at SAMPLES times to its end and through each contact before the top ball's
        first apex (docs/performance.md, "The Stack scene's forces": one run a move, where
        there were two, the first to learn the time span)."""
        first = result.apex_t[0] if result.apex_t else result.end_time
        contacts = [(c.start, min(c.end, first)) for c in result.contacts if c.start < first]
        through_each = max(2, min(9, CONTACT_SAMPLES // max(len(contacts), 1)))
        times = np.unique(
            np.concatenate(
                [np.linspace(0.0, result.end_time, SAMPLES)]
                + [np.linspace(start, end, through_each) for start, end in contacts]
            )
        )
        result.trajectory = result.evaluate(times)
        return result

    @param.depends("revision", watch=True)
    def _draw(self, *events: param.parameterized.Event) -> None:
        if not self.active:
            return
        self.current()
        self._dim()
        r = self.result
        if self.refused is not None:  # the summary says why; the last stack's plots stay, dimmed
            self.refusals.data = {"n": [self.computations]}  # (answers the change)
            return
        if r is None:
            return
        if self.refusals.data["n"]:  # back from a refusal: (answers the change; the stack
            self.refusals.data = {"n": []}  # carried again may bring the same data as before)
        tr = r.trajectory
        n = r.stack.balls
        self._add_lines(n)
        data = {"t": on_screen(tr.t)}
        for ball in range(len(self._lines)):  # (every line's column, NaN for a ball not there)
            data[f"x{ball}"] = on_screen(tr.x[:, ball] if ball < n else np.full(tr.t.size, np.nan))
        self.curves.data = data
        for ball, item in enumerate(self.legend.items):
            item.visible = ball < n
        top = r.apexes[-1]
        self.apexes.data = {
            "t": [t for t, _ in top],
            "h": [h for _, h in top],
            "text": [f"h{i + 1} = {number_text(h)}" for i, (_, h) in enumerate(top)],
            "align": ["center" if i == 0 else "right" for i in range(len(top))],
            "dx": [0 if i == 0 else -6 for i in range(len(top))],
        }
        icm = icm_chain(r.stack)[-1]
        self.icm_line.location = icm
        highest = max(float(np.nanmax(tr.x)), icm)
        # room above the highest apex for its label (larger on a projector: 16 pt)
        low, high = -0.03 * highest, (1.25 if self.state.presentation else 1.12) * highest
        self.heights.y_range.update(start=low, end=high, reset_start=low, reset_end=high)
        # the stack's top at ``high`` at most: each ball at its height, on the balls below
        room = low + (high - low) / (1 - 2 * ball_sizes(r.stack.masses).sum())
        self.animation.y_range.update(start=low, end=room, reset_start=low, reset_end=room)
        self._animate()

    def _animate(self) -> None:
        """The animation of this stack, played in the browser (app/animation.py): each ball
        on its height, stacked, ball i standing on ball i-1 when X_i = X_(i-1) (their overlap
        is the compression); radii follow the masses (equal density, :func:`ball_sizes`). The
        frames are the solver's at their times, in a run of their own when the player first
        moves; the frame on screen now is read off the plotted curves."""
        r = self.result
        span = self.animation.y_range.end - self.animation.y_range.start
        radii = span * ball_sizes(r.stack.masses)
        below = np.concatenate([[0.0], np.cumsum(2 * radii)[:-1]]) + radii
        frame = min(self.player.value_throttled, self.times.size - 1)
        tr = r.trajectory
        now = [np.interp(self.times[frame], tr.t, tr.x[:, b]) for b in range(r.stack.balls)]
        arguments, options = self._run

        def frames() -> list[np.ndarray]:
            run = simulate_stack(*arguments, **options, until=r.end_time, t_eval=self.times)
            return [run.trajectory.x[:, ball] + below[ball] for ball in range(r.stack.balls)]

        self.animated.show(
            self.times,
            list(np.array(now) + below),
            frames,
            list(radii),
            list(PALETTE),
            at=frame,
            unit="tau",
            slow=self.slow,
        )

    def _summary_text(self) -> str:
        r = self.result
        s = self.state
        if not r.success:
            return f"**The solver could not finish this stack** ({r.status.message})."
        icm = icm_chain(r.stack)[-1]
        drop = r.stack.x_start[-1]
        first = "no first bounce" if r.h1 is None else (
            f"the top ball rises to **h1 = {number_text(r.h1)}**{below_zero(r.h1)}, "
            # (its own release height, the stack's H plus the balls below it: "times its drop
            # height" read as h1/H, which it is not)
            f"{times_text(r.h1 / drop)} times its release height {number_text(drop)}"
        )  # fmt: skip
        second = (
            ""
            if r.h2 is None
            else f"; then h2 = {number_text(r.h2)}{below_zero(r.h2)} (h2/h1 = {r.h2 / r.h1:.3f})"
        )
        counts = ", ".join(
            ("floor" if c == 0 else f"{c}-{c + 1}") + f": {k}"
            for c, k in enumerate(r.contacts_first)
        )
        ratio = "" if r.h1 is None else f" (h1/chain = {r.h1 / icm:.3f})"
        eps = [float(e) for e in r.stack.eps]
        if contact_eps(s.stack_eps_contacts, s.balls)[0] is not None:  # typed, "advanced"
            # (said even when all are equal: 0.5 typed for every contact left the slider's 0.9
            # on screen, with nothing saying it was not used)
            first = f"eps per contact {', '.join(f'{e:g}' for e in eps)}; {first}"
        # (on a projector the contact counts are left out: eight balls' list took the summary
        # to five lines, and the player off the screen)
        contacts = (
            "" if s.presentation else f" Contacts before h1 (floor, then each pair): {counts}."
        )
        # (the switch in the sidebar says metres, seconds: say here that this scene has none)
        units = (
            " Dimensionless heights and times: the stacks have no metres."
            if s.units == "SI"
            else ""
        )
        return (
            f"{s.balls} balls, {s.force} force: {first}{second}.  \n"
            f"Chain of independent collisions (dotted green): {number_text(icm)}{ratio}."
            f"{contacts}{units}"
        )

    def own_controls(self) -> pn.viewable.Viewable:
        """The stack's sliders, its force and its eps per contact, for the sidebar."""
        return self._controls

    def _dim(self) -> None:
        """The plots dimmed while they show the last stack carried, not the one asked for."""
        # (not {}: BokehJS keeps a style that is dropped rather than set)
        for plot in self._plots:
            plot.styles = {"opacity": "0.35" if self.refused is not None else "1"}

    def layout(self) -> pn.viewable.Viewable:
        if on_a_phone() and not self.state.presentation:
            # the stack's sliders (not its force, nor eps per contact) right under the heights,
            # as the Drop's (the sidebar's lay under the player and the explanation: a
            # teacher's trial); never dimmed, they are what undoes a refused stack
            self._plots = [
                pn.pane.Bokeh(self.heights, sizing_mode="stretch_width"),
                pn.pane.Bokeh(self.animation),
            ]
            sliders = phone_only(*self._sliders(), css_class="twoball-phone-sliders")
            plots = pn.Column(self._plots[0], sliders, self._plots[1], sizing_mode="stretch_width")
        else:
            plots = heights_and_stage(self.heights, self.animation, self.state.presentation)
            self._plots = [plots]
        self._draw()
        self._dim()
        if self.state.presentation:
            caption = pn.pane.Markdown(
                PROJECTED_CAPTION,
                height=PROJECTED_PLAYER_HEIGHT,
                sizing_mode="stretch_width",
                stylesheets=[PROJECTED_CAPTION_CSS],
                styles={"flex": "1 1 0", "min-width": "0"},  # (the player keeps its width)
                css_classes=["twoball-stack-caption"],
            )
            self.player.styles = {"flex": "none"}  # (squeezed, its buttons ran out of it)
            player = pn.Row(self.player, caption, sizing_mode="stretch_width")
            return pn.Column(self.summary, plots, player, sizing_mode="stretch_width")
        caption = pn.pane.Markdown(CAPTION_HELP, sizing_mode="stretch_width")
        return pn.Column(self.summary, plots, self.player, caption, sizing_mode="stretch_width")
