"""Scene 4, accuracy: error against run time of every integrator at the current drop.

The work is :func:`twoball.studies.precision.work_precision` (a few seconds); it runs in a thread
only while the scene is on screen, with a line saying so, and a newer request supersedes an
older one.
"""

from __future__ import annotations

import asyncio
import functools
import math

import panel as pn
import param
from bokeh.models import ColumnDataSource, Legend, LegendItem, Line, Range1d, Scatter
from bokeh.plotting import figure

from twoball import warmup
from twoball.studies.precision import ERROR_FLOOR, FAILED_ERROR, PrecisionRow, work_precision

from .controls import PhoneSliders, on_a_phone
from .scene import (
    MODEL_PARAMETERS,
    PROJECTOR_LINE_WIDTH,
    AnsweringMarkdown,
    Scene,
    Text,
    draw,
    readable,
)
from .state import ExplorerState
from .steps import STEPS

# Okabe and Ito's eight colours, told apart with every common colour-vision deficiency (black
# first: the exact solver, pale yellow last); Category10's red and green were not
OKABE_ITO = ("#000000", "#E69F00", "#56B4E9", "#009E73", "#0072B2", "#D55E00", "#CC79A7", "#F0E442")
STALE = {"opacity": "0.35"}  # the results of the drop before, while this one is measured
# presentation mode (scene.py): first under the tabs, and the explanation under it, in 720 px
PROJECTOR_PLOT_HEIGHT = 380
# On a projector the plot's neighbour: the rows at one tolerance, the lesson's question's (6
# digits asked for). The whole table (21 rows, 770 px at a room's 20 px) lay under the plot,
# off a 1280x720 screen (the lesson's step 6: a teacher's trial); it is left out there.
ASKED_TOLERANCE = 1e-6
PROJECTOR_ASKED_WIDTH = 360


def log_range(values: list[float], empty: tuple[float, float]) -> Range1d:
    """An axis range on a log scale around ``values`` with a tenth of their span (in decades,
    at least one) to spare on each side, so that points at the ends are not cut in half;
    ``empty`` where there are none."""
    logs = [math.log10(v) for v in values if v > 0]
    if not logs:
        return Range1d(*empty)
    low, high = min(logs), max(logs)
    spare = 0.1 * max(high - low, 1.0)
    return Range1d(10 ** (low - spare), 10 ** (high + spare))


@functools.lru_cache(maxsize=64)
def measured(
    eps: float, mu: float, tau_ratio: float, eps12: float | None, height: float, compiled: bool
) -> tuple[PrecisionRow, ...]:
    """The work-precision rows of a drop, measured once per server process and state of the
    compiler (``compiled``: the two-ball solver's kernels in use, :func:`twoball.warmup.in_use`):
    a class opening the scene at one lesson step's drop costs the server one measurement (a few
    seconds of CPU), not one a student. The run times shown are those of that first
    measurement; one made while the kernels were still compiling (their Python stand-ins: the
    exact solver 2.8 ms, LSODA 0.8 s) is measured again once they are compiled, not kept for
    the rest of the server's life."""
    return tuple(work_precision(eps, mu, tau_ratio, eps12=eps12, height=height))


def measure_ahead() -> None:
    """Measure the drops a class opens this scene on (the explorer's default drop, and the
    lesson's step that shows this scene) into :func:`measured`'s cache, once the kernels are
    compiled (``app_hooks`` calls it then, off the event loop): a teacher found the first
    visit blank for 3.6 s, and the lesson's reveal there took 7 s on a busy server."""
    default = ExplorerState()
    drops = [{name: getattr(default, name) for name in MODEL_PARAMETERS}]
    drops += [step.drop for step in STEPS if step.scene == "accuracy"]
    for drop in drops:
        measured(drop["eps"], drop["mu"], drop["tau_ratio"], drop["eps12"], drop["height"], True)


class AccuracyScene(Scene):
    """Work-precision diagram at the current parameters, computed only when opened."""

    watched = ("eps", "eps12", "mu", "tau_ratio", "height")

    def __init__(self, **params):
        super().__init__(**params)
        self.rows: list[PrecisionRow] | None = None
        self._request = 0
        self._measuring = False  # (a thread measures for this page: _measure_in_thread)
        # a new Bokeh figure per result (the number of methods drawn varies; a figure built
        # whole arrives whole in the browser); drawn by HoloViews, a result cost about ten
        # times as much, and the scene's opening twice the others'
        # (none until the first result: a figure without renderers is a mistake Bokeh reports)
        self.plot = pn.pane.Bokeh(None, sizing_mode="stretch_width")
        # every method's rows at every tolerance; not on a projector, where the rows at the
        # asked tolerance stand beside the plot and the whole table ran 800 px below the screen
        self.table = (
            None
            if self.state.presentation
            else Text(pn.bind(self._table, self.param.revision), sizing_mode="stretch_width")
        )
        # what is being computed, said in words (Panel's loading overlay, set back from the
        # computation's callback, sometimes stayed on in the browser though the plots arrived)
        # ("Computing..." answers a move)
        self.status = AnsweringMarkdown("", sizing_mode="stretch_width")
        about = pn.pane.Markdown(
            # (on a projector in two lines: three ran under a 1280x720 screen's foot)
            f"Error of h1, h2 against the exact solver (drawn at {ERROR_FLOOR:.0e}) and run "
            "time, for each scipy method at rtol = atol = 1e-3, 1e-6, 1e-9; an error of "
            f"{FAILED_ERROR:g}: failed or missed a bounce."
            if self.state.presentation
            else "Relative error of h1 and h2 (the larger) against the exact solver, and the "
            "run time to the second apex, for each scipy integrator at rtol = atol = "
            "1e-3, 1e-6, 1e-9. The exact solver is the reference: its error is drawn at "
            f"{ERROR_FLOOR:.0e}. An error of {FAILED_ERROR:g}: the method failed or missed a "
            "bounce."
        )
        # on a projector the plot comes first, under the tabs (the teacher says what it shows),
        # with the rows at the asked tolerance beside it (ASKED_TOLERANCE)
        if self.state.presentation:
            asked = Text(
                pn.bind(self._asked_table, self.param.revision), width=PROJECTOR_ASKED_WIDTH
            )
            parts = [pn.Row(self.plot, asked, sizing_mode="stretch_width"), about]
        else:
            parts = [about, self.plot]
        # the last drop's plot and table, dimmed while the next is measured (at full strength
        # they were read as the new drop's for the few seconds of the measurement)
        if self.table is not None:
            parts.append(self.table)
        self.results = pn.Column(*parts, sizing_mode="stretch_width")
        self._dimmed = [self.results]
        self.view = pn.Column(self.status, self.results, sizing_mode="stretch_width")

    def _state_changed(self, *events: param.parameterized.Event) -> None:
        if self.active:
            self._start()

    @param.depends("active", watch=True)
    def _activated(self) -> None:
        if self.active:
            self._start()

    def _start(self) -> None:
        """Measure the drop in a thread (under a server), unless its rows are already those
        shown or being measured."""
        if self.inputs() == self._computed_for:
            return
        self._computed_for = self.inputs()
        self._request += 1
        self.status.object = (
            "*Computing: every method at every tolerance on this drop (a few seconds)...*"
        )
        if self.rows is not None:
            self._dim(STALE)
        document = pn.state.curdoc
        if document is not None and document.session_context is not None:
            if not self._measuring:  # (else the running measurement takes the newest next)
                self._measuring = True
                pn.state.execute(functools.partial(self._measure_in_thread, document))
        else:  # no server (a script or a test): compute now
            self._show(self._request, self._work())

    def inputs(self) -> tuple:
        """The drop, and whether the kernels are compiled (:func:`measured`)."""
        return (*super().inputs(), warmup.in_use("two-ball"))

    def _work(self) -> list[PrecisionRow]:
        s = self.state
        self.computations += 1
        compiled = warmup.in_use("two-ball")
        return list(measured(s.eps, s.mu, s.tau_ratio, s.eps12, s.height, compiled))

    async def _measure_in_thread(self, document) -> None:
        """Measure in a thread until the drop measured is the newest asked for, then show it.

        One measurement at a time per page: the moves made meanwhile are taken together, by
        measuring the newest once this one ends. (Each move had started a thread of its own:
        five key presses on a slider ran five measurements side by side, each slower for the
        others, and the last drop showed after 20 s, a teacher's trial.)"""
        try:
            while True:
                request = self._request
                rows = await asyncio.to_thread(self._work)
                if request == self._request:
                    break
        finally:
            self._measuring = False
        # Shown on the next tick of this session's own document, under its lock: Panel runs the
        # coroutine with no current document (or another session's).
        document.add_next_tick_callback(functools.partial(self._show, request, rows))

    def _show(self, request: int, rows: list[PrecisionRow]) -> None:
        if request != self._request:
            return  # superseded by a newer drop
        self.rows = rows
        self.revision = True
        self.status.object = ""
        self._dim({"opacity": "1"})

    def _dim(self, styles: dict[str, str]) -> None:
        for shown in self._dimmed:
            shown.styles = styles

    @param.depends("revision", watch=True)
    def _draw(self) -> None:
        self.plot.object = self._figure(self.rows) if self.rows else None

    def _figure(self, rows: list[PrecisionRow]):
        """Error against run time, both logarithmic, a line and its points per method, the
        legend below the plot in rows (beside it, on a phone, it took half the width; a
        projector has the width, not the height)."""
        projected = self.state.presentation
        points = {
            method: [(r.seconds, r.shown_error) for r in rows if r.method == method]
            for method in dict.fromkeys(r.method for r in rows)
        }
        points = {m: [p for p in shown if math.isfinite(p[0])] for m, shown in points.items()}
        everything = [p for shown in points.values() for p in shown]
        fig = figure(
            title="Error against run time",
            x_axis_type="log",
            y_axis_type="log",
            x_range=log_range([p[0] for p in everything], (1e-5, 1.0)),
            y_range=log_range([p[1] for p in everything], (ERROR_FLOOR, 1.0)),
            x_axis_label="run time per drop [s]",
            y_axis_label="error of h1, h2" if projected else "relative error of h1, h2 (larger)",
            height=PROJECTOR_PLOT_HEIGHT if projected else 480,
            sizing_mode="stretch_width",
            tools="pan,box_zoom,wheel_zoom,reset,save",
        )
        fig.toolbar.autohide = True
        line, size = (PROJECTOR_LINE_WIDTH, 14) if projected else (2, 8)
        items = []
        for (method, shown), colour in zip(points.items(), OKABE_ITO, strict=False):
            source = ColumnDataSource(
                {"seconds": [p[0] for p in shown], "error": [p[1] for p in shown]}
            )
            glyphs = (
                Line(x="seconds", y="error", line_color=colour, line_width=line),
                Scatter(x="seconds", y="error", size=size, fill_color=colour, line_color=colour),
            )
            renderers = [draw(fig, glyph, source) for glyph in glyphs]
            items.append(LegendItem(label=method, renderers=renderers))
        legend = Legend(items=items, spacing=6, ncols=1 if projected else 3)
        fig.add_layout(legend, "right" if projected else "below")
        readable(fig, projected)
        return fig

    def _table(self, revision: bool) -> str:
        if not self.rows:
            return ""
        exact = next(r for r in self.rows if r.tolerance is None)
        if math.isnan(exact.rel_err_h1):
            return (
                "**This drop has no bounce to measure:** the upper ball comes to rest on the "
                "lower one (the Drop scene shows it), so there is no h1 or h2 to compare the "
                "methods on. Choose a bouncier drop (a larger eps) to compare them."
            )
        lines = []
        if math.isnan(exact.rel_err_h2):
            lines += ["*No second bounce in this drop: the errors are those of h1 alone.*", ""]
        lines += ["| method | tolerance | error h1 | error h2 | seconds |", "|---|---|---|---|---|"]
        for r in self.rows:
            tol = "-" if r.tolerance is None else f"{r.tolerance:.0e}"
            lines.append(
                f"| {r.method} | {tol} | {r.rel_err_h1:.2e} | {r.rel_err_h2:.2e} "
                f"| {r.seconds:.3g} |"
            )
        return "\n".join(lines)

    def _asked_table(self, revision: bool) -> str:
        """The exact solver's row and each method's at :data:`ASKED_TOLERANCE`: its error (the
        larger of h1's and h2's) and run time."""
        rows = [
            r
            for r in self.rows or []
            if r.tolerance is None or math.isclose(r.tolerance, ASKED_TOLERANCE)
        ]
        if not rows or math.isnan(rows[0].rel_err_h1):
            return ""  # (the table below says why: no bounce to measure)
        digits = round(-math.log10(ASKED_TOLERANCE))
        lines = [
            f"**Asked for {digits} digits (tolerance 1e-{digits}):**",
            "",
            "| method | error | seconds |",
            "|---|---|---|",
        ]
        for r in rows:
            error = "failed" if r.failed else f"{r.error:.1e}"
            if r.tolerance is None:
                error = "(reference)"
            lines.append(f"| {r.method} | {error} | {r.seconds:.2g} |")
        return "\n".join(lines)

    def layout(self) -> pn.viewable.Viewable:
        if on_a_phone() and not self.state.presentation:
            # the two-ball sliders right under the plot, as on the Drop (the sidebar's lay
            # under the table's 21 rows: a teacher's trial), never dimmed: the plot and the
            # table are, each apart, while the next drop is measured
            table = pn.Column(self.table, styles=self.results.styles, sizing_mode="stretch_width")
            self.results.remove(self.table)
            self._dimmed.append(table)
            self.view.extend([PhoneSliders(state=self.state), table])
        return self.view
