"""Scene 4, accuracy: error against run time of every integrator at the current drop.

The work is :func:`twoball.studies.precision.work_precision` (a few seconds); it runs in a thread
only while the scene is on screen, with a line saying so, and a newer request supersedes an
older one.
"""

from __future__ import annotations

import asyncio
import functools
import math

import holoviews as hv
import panel as pn
import param

from twoball import jit
from twoball.studies.precision import ERROR_FLOOR, FAILED_ERROR, PrecisionRow, work_precision

from .scene import PROJECTOR_LINE_WIDTH, AnsweringMarkdown, Scene, Text, font_sizes

# Okabe and Ito's eight colours, told apart with every common colour-vision deficiency (black
# first: the exact solver, pale yellow last); Category10's red and green were not
OKABE_ITO = ("#000000", "#E69F00", "#56B4E9", "#009E73", "#0072B2", "#D55E00", "#CC79A7", "#F0E442")
STALE = {"opacity": "0.35"}  # the results of the drop before, while this one is measured
PROJECTOR_PLOT_HEIGHT = 400  # presentation mode (scene.py): first under the tabs, in 720 px


@functools.lru_cache(maxsize=64)
def measured(
    eps: float, mu: float, tau_ratio: float, eps12: float | None, height: float, compiled: bool
) -> tuple[PrecisionRow, ...]:
    """The work-precision rows of a drop, measured once per server process and state of the
    compiler (``compiled``: :data:`twoball.jit.state`): a class opening the scene at one lesson
    step's drop costs the server one measurement (a few seconds of CPU), not one a student.
    The run times shown are those of that first measurement; one made while the kernels were
    still compiling (their Python stand-ins: the exact solver 2.8 ms, LSODA 0.8 s) is measured
    again once they are compiled, not kept for the rest of the server's life."""
    return tuple(work_precision(eps, mu, tau_ratio, eps12=eps12, height=height))


class AccuracyScene(Scene):
    """Work-precision diagram at the current parameters, computed only when opened."""

    watched = ("eps", "eps12", "mu", "tau_ratio", "height")

    def __init__(self, **params):
        super().__init__(**params)
        self.rows: list[PrecisionRow] | None = None
        self._request = 0
        # a new figure per result (rare): the number of methods drawn varies
        self.plot = pn.pane.HoloViews(
            pn.bind(self._plot, self.param.revision), sizing_mode="stretch_width"
        )
        self.table = Text(pn.bind(self._table, self.param.revision), sizing_mode="stretch_width")
        # what is being computed, said in words (Panel's loading overlay, set back from the
        # computation's callback, sometimes stayed on in the browser though the plots arrived)
        # ("Computing..." answers a move)
        self.status = AnsweringMarkdown("", sizing_mode="stretch_width")
        about = pn.pane.Markdown(
            "Relative error of h1 and h2 (the larger) against the exact solver, and the "
            "run time to the second apex, for each scipy integrator at rtol = atol = "
            "1e-3, 1e-6, 1e-9. The exact solver is the reference: its error is drawn at "
            f"{ERROR_FLOOR:.0e}. An error of {FAILED_ERROR:g}: the method failed or missed a "
            "bounce."
        )
        # on a projector the plot comes first, under the tabs (the teacher says what it shows)
        parts = [self.plot, about] if self.state.presentation else [about, self.plot]
        # the last drop's plot and table, dimmed while the next is measured (at full strength
        # they were read as the new drop's for the few seconds of the measurement)
        self.results = pn.Column(*parts, self.table, sizing_mode="stretch_width")
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
            self.results.styles = STALE
        document = pn.state.curdoc
        if document is not None and document.session_context is not None:
            pn.state.execute(functools.partial(self._compute_in_thread, self._request, document))
        else:  # no server (a script or a test): compute now
            self._show(self._request, self._work())

    def inputs(self) -> tuple:
        """The drop, and whether the kernels are compiled (:func:`measured`)."""
        return (*super().inputs(), jit.state == "compiled")

    def _work(self) -> list[PrecisionRow]:
        s = self.state
        self.computations += 1
        compiled = jit.state == "compiled"
        return list(measured(s.eps, s.mu, s.tau_ratio, s.eps12, s.height, compiled))

    async def _compute_in_thread(self, request: int, document) -> None:
        rows = await asyncio.to_thread(self._work)
        # Shown on the next tick of this session's own document, under its lock: Panel runs the
        # coroutine with no current document (or another session's).
        document.add_next_tick_callback(functools.partial(self._show, request, rows))

    def _show(self, request: int, rows: list[PrecisionRow]) -> None:
        if request != self._request:
            return  # superseded by a newer drop
        self.rows = rows
        self.param.trigger("revision")
        self.status.object = ""
        self.results.styles = {"opacity": "1"}

    def _plot(self, revision: bool) -> hv.Overlay:
        time_dim = hv.Dimension("seconds", label="run time per drop [s]")
        label = (
            "error of h1, h2" if self.state.presentation else "relative error of h1, h2 (larger)"
        )
        error_dim = hv.Dimension("error", label=label)
        layers = []
        methods = dict.fromkeys(r.method for r in self.rows or [])
        for method, color in zip(methods, OKABE_ITO, strict=False):
            mine = [r for r in self.rows if r.method == method and math.isfinite(r.seconds)]
            points = [(r.seconds, r.shown_error) for r in mine]
            line, size = (PROJECTOR_LINE_WIDTH, 14) if self.state.presentation else (2, 8)
            layers.append(
                hv.Curve(points, time_dim, error_dim, label=method).opts(
                    color=color, line_width=line
                )
            )
            layers.append(
                hv.Scatter(points, time_dim, error_dim, label=method).opts(color=color, size=size)
            )
        if not layers:
            layers = [hv.Curve([], time_dim, error_dim)]
        projected = self.state.presentation
        return hv.Overlay(layers).opts(
            hv.opts.Overlay(
                logx=True,
                logy=True,
                responsive=True,
                height=PROJECTOR_PLOT_HEIGHT if projected else 480,
                framewise=True,
                padding=0.1,  # points at the ends of the axes are not cut in half
                fontsize=font_sizes(self.state.presentation),
                # below the plot, in rows: beside it, on a phone, it took half its width (a
                # projector has the width, not the height)
                legend_position="right" if projected else "bottom",
                legend_cols=1 if projected else 3,
                legend_opts={"spacing": 6},
                title="Error against run time",
            )
        )

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

    def layout(self) -> pn.viewable.Viewable:
        return self.view
