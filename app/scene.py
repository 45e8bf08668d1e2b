"""What every scene shares: it recomputes only while it is on screen, and only when stale."""

from __future__ import annotations

import textwrap
from collections.abc import Callable
from html import escape

import numpy as np
import panel as pn
import param
from bokeh.models import ColumnDataSource, CustomJS, GlyphRenderer, LabelSet, Span
from bokeh.models.glyph import Glyph
from markdown_it import MarkdownIt

from .state import ExplorerState

MODEL_PARAMETERS = ("eps", "eps12", "mu", "tau_ratio", "height")
# Presentation mode (?present=1) lays every scene out for the smaller projector, 1280 x 720
# (1366 x 768 then fits too): about 560 px are left under the header and the tabs, so each
# scene's plots get a height of their own there, and lines and markers are drawn bolder.
PROJECTOR_LINE_WIDTH = 4
PROJECTOR_MARKER_SIZE = 14
# Bootstrap's pale alert text (cyan on pale cyan) fails WCAG contrast (axe-core): darker text
ALERT_CSS = ":host, :host * { color: #1b1e21 !important; }"


def later(callback) -> None:
    """Run ``callback`` on the session's next tick (at once without a server).

    Bokeh models changed inside the callback of a change made in the browser (a typed value, a
    tab chosen) either raised "_pending_writes should be non-None when we have a document lock"
    or were not sent back to that browser; on the next tick the document is locked by Bokeh
    with its pending writes set, and every change is sent.
    """
    document = pn.state.curdoc
    if document is None or document.session_context is None:
        callback()
    else:
        document.add_next_tick_callback(callback)


def send_without_delay() -> None:
    """Send this session's messages at once (TCP_NODELAY on its websocket).

    A Bokeh message is several websocket frames (header, metadata, content, buffers); Tornado
    leaves Nagle's algorithm on, so every frame after the first waited for the browser's delayed
    ACK: about 40 ms more for each message, 90 ms between a slider's release and the redrawn
    plot even for a minimal Panel app (benchmarks/app_load.py, tools/bokehclient.py). Bokeh
    3.9 offers no option for it; the socket is reached through the session's connections
    (private attributes, hence the guards: without them the page still works, slower). Call
    once the page has loaded (``pn.state.onload``), when its websocket is connected.
    """
    document = pn.state.curdoc
    session = getattr(getattr(document, "session_context", None), "_session", None)
    for connection in getattr(session, "_subscribed_connections", ()):
        socket = getattr(connection, "_socket", None)
        if hasattr(socket, "set_nodelay"):
            socket.set_nodelay(True)


def join(layout: pn.layout.ListLike | None, pane: pn.viewable.Viewable, at: int = 0) -> None:
    """Put ``pane`` into ``layout`` at ``at`` unless it is there (or the layout is not built
    yet): a pane that joins the page when first needed, not in every page's first document."""
    if layout is not None and pane not in layout.objects:
        layout.insert(at, pane)


# a fold's button, as a card's title: its words at the left, in bold, on the card's grey
FOLD_CSS = """
:host .bk-btn { text-align: left; font-weight: 600; background-color: #f8f9fa; }
:host .bk-btn.bk-active { background-color: #e2e6ea; }
"""


class Folded:
    """Inputs folded away under a button, as in a collapsed card: pressed, the button shows
    them below it (made then, the first time) and, pressed again, hides them.

    A collapsed ``pn.Card`` cost every page about 5 ms of server CPU to open (its header row,
    title pane and card model: benchmarks/app_open.py), though few pages open it; the button
    costs about 1 ms. ``contents`` makes the inputs; the button (``button``) goes into a layout
    of the caller's (:meth:`place`), the inputs after it once opened."""

    def __init__(self, title: str, contents: Callable[[], list[pn.viewable.Viewable]]):
        self.button = pn.widgets.Toggle(
            label=title, value=False, sizing_mode="stretch_width", stylesheets=[FOLD_CSS]
        )
        self._contents = contents
        self.body: pn.Column | None = None
        self._layout: pn.layout.ListLike | None = None
        self.button.param.watch(self._pressed, "value")

    def place(self, layout: pn.layout.ListLike) -> pn.widgets.Toggle:
        """The button, for ``layout``, where the inputs will go after it."""
        self._layout = layout
        return self.button

    @property
    def opened(self) -> bool:
        return self.button.value

    def open(self) -> None:
        self.button.value = True

    def _pressed(self, event: param.parameterized.Event) -> None:
        if event.new and self.body is None:
            self.body = pn.Column(*self._contents(), sizing_mode="stretch_width")
        if self.body is None:
            return
        if self._layout is not None and self.body not in self._layout.objects:
            self._layout.insert(self._layout.objects.index(self.button) + 1, self.body)
        self.body.visible = event.new


class Built(pn.viewable.Viewer):
    """A viewer whose layout is built once, by :meth:`layout`, and returned by ``__panel__``
    from then on (its widgets and figures keep their Bokeh models for the session)."""

    _layout: pn.viewable.Viewable | None = None

    def layout(self) -> pn.viewable.Viewable:
        raise NotImplementedError

    def __panel__(self) -> pn.viewable.Viewable:
        if self._layout is None:
            self._layout = self.layout()
        return self._layout


class Scene(Built):
    """A scene of the explorer. Subclasses implement :meth:`update` and :meth:`layout`, and name
    in ``watched`` the state's parameters a change of which redraws them.

    While the scene is on screen (``active``) a change of a watched parameter fires
    ``revision``, on which its views depend. Each view calls :meth:`current` first, which runs
    :meth:`update` only when :meth:`inputs` differ from those of the last update: the work is
    done once per change, and only for a scene that is drawn. A scene off screen is redrawn
    when it comes back, recomputed only if its inputs changed meanwhile.
    """

    state = param.ClassSelector(class_=ExplorerState, doc="The session's shared state.")
    active = param.Boolean(default=False, doc="Whether the scene is on screen.")
    revision = param.Event(doc="Fires when the scene must redraw (its views depend on it).")

    watched: tuple[str, ...] = (*MODEL_PARAMETERS, "units")

    def __init__(self, **params):
        super().__init__(**params)
        self.computations = 0
        self._computed_for: tuple | None = None  # the inputs of the last update
        # (a watcher, not @param.depends: each scene class names its own ``watched``)
        self.state.param.watch(self._state_changed, list(self.watched))

    def inputs(self) -> tuple:
        """What :meth:`update` reads: by default the watched parameters' values; a scene that
        reads more (or less) says so here."""
        return tuple(getattr(self.state, name) for name in self.watched)

    def _state_changed(self, *events: param.parameterized.Event) -> None:
        if self.active:
            self.redraw_now()

    @param.depends("active", watch=True)
    def _activated(self) -> None:
        # redrawn each time it comes back on screen (recomputed only if stale); on its first
        # visit its layout, built after this, draws it (redrawn too, a page's opening drew the
        # Stack twice: 3 ms of its 105, benchmarks/app_open.py)
        if self.active and self._layout is not None:
            later(self._redraw)

    def _redraw(self) -> None:
        if self.active:  # (a text bound to ``active`` may have recomputed it meanwhile)
            self.redraw_now()

    def redraw_now(self) -> None:
        """Fire ``revision``, every change it makes to the page sent as one message (each
        change was a message of its own: 16 for a move of the drop scene)."""
        with pn.io.hold():
            self.revision = True

    def current(self) -> None:
        """Recompute what the scene shows if its inputs changed since the last update; every
        view calls this first."""
        inputs = self.inputs()
        if inputs != self._computed_for:
            self._computed_for = inputs
            self.computations += 1
            self.update()

    def update(self) -> None:
        raise NotImplementedError

    def own_controls(self) -> pn.viewable.Viewable | None:
        """The scene's own sliders, shown in the sidebar in place of the two-ball ones while
        the scene is on screen; None for a scene the two-ball sliders drive."""
        return None


# A change the server has not answered yet: a slider's release marks the page (a class on its
# body: the plots dim and a banner says so, PAGE_CSS in explorer.py) until the scene's data
# arrive, all in the browser (nothing sent back). With a class moving sliders at once the server
# may be seconds behind; stale plots must not look current. A change that brings no new data
# (e.g. a value the slider already had) clears it after 30 s. The functions are in
# app/static/pending.js, loaded once with the page (app/main.py), not in every document.
PENDING_JS = "twoballPending();"
ANSWERED_JS = "twoballAnswered();"


def answers_pending(source) -> None:
    """A Bokeh ColumnDataSource whose new data answer the last change (the page is current)."""
    source.js_on_change("data", CustomJS(code=ANSWERED_JS))


# The page's design (explorer.ClassroomPage, Panel's Bootstrap page): a Text pane has it as its
# own, so its model is made with the design's style sheets for a component of its own (below)
PAGE_DESIGN = pn.theme.Bootstrap


# The texts' Markdown: CommonMark with tables, all that the scenes' texts use. Panel's parser
# (GFM-like, with bare links, footnotes, definition lists, task lists, emoji and heading
# anchors) gives the same HTML for them (tests/app/test_app_scenes.py compares every text of
# every scene) and took twice as long: 0.18 against 0.09 ms a summary, a tenth of a stack
# move's scene work (cProfile, 100 moves)
TEXT_MARKDOWN = MarkdownIt("commonmark").enable("table")


class Text(pn.pane.Markdown):
    """A Markdown pane whose change sends its new text alone.

    Panel's own update of a Markdown pane recomputed all of the pane's properties (its design's
    style sheets among them, each resolved from a file path) and set them on the model again:
    the drop scene's summary took 44 % of the scene's update, a tenth of a slider move's server
    CPU (py-spy, 200 served moves). Only the text depends on what changes here (the object, or
    how it is rendered: Panel's ``_rerender_params``), so only the text is set.

    The pane has the page's design as its own (:data:`PAGE_DESIGN`): Panel makes its model with
    the style sheets of a component styled on its own (Bootstrap's, the theme's), which the
    template's pass then leaves alone; without a design of its own the template gave the model
    fewer (the text stood 20 px lower), and Panel's update (which always adds them) brought them
    after the page had loaded, an update of the whole pane and of the document's models."""

    def __init__(self, object=None, **params):
        params.setdefault("design", PAGE_DESIGN)
        super().__init__(object, **params)

    def _update(self, ref: str, model) -> None:
        model.text = self._transform_object(self.object)["object"]

    def _transform_object(self, obj: object) -> dict[str, str]:
        """The text as HTML, escaped as Panel sends it, parsed by :data:`TEXT_MARKDOWN`."""
        text = "" if obj is None else obj if isinstance(obj, str) else obj._repr_markdown_()
        return {
            "object": escape(TEXT_MARKDOWN.render(textwrap.dedent(text) if self.dedent else text))
        }


class AnsweringMarkdown(Text):
    """A Markdown pane whose new text answers the last change (as :func:`answers_pending`).

    The callback goes on the pane's Bokeh model: Panel's ``jscallback`` on a pane added to a page
    already shown (a scene built when first visited) sent a CustomJS the browser could not
    connect ("Cannot read properties of undefined (reading 'connect')" in its console)."""

    def _get_model(self, doc, root=None, parent=None, comm=None):
        model = super()._get_model(doc, root, parent, comm)
        model.js_on_change("text", CustomJS(code=ANSWERED_JS))
        return model


class ScriptedButton(pn.widgets.Button):
    """A button that also runs ``script`` in the browser when clicked (app/static), set on its
    Bokeh model.

    Panel's ``js_on_click`` registers a link, and from the first one in a server process Panel
    looks for links through every model of every page it builds, each time one of the page's
    roots is made: 3 ms of a page's opening (benchmarks/app_open.py), for the lesson's Start
    button alone."""

    script = param.String(doc="JavaScript run in the browser at each click.")

    _rename = {**pn.widgets.Button._rename, "script": None}  # (not a property of the model)

    def _get_model(self, doc, root=None, parent=None, comm=None):
        model = super()._get_model(doc, root, parent, comm)
        model.js_on_event("button_click", CustomJS(code=self.script))
        return model


# a row whose items wrap onto the next line where the screen is too narrow for them (a phone)
WRAPS = ":host { flex-wrap: wrap; }"


def wrapping_row(*objects, **params) -> pn.Row:
    """A row whose items wrap onto the next line on a narrow screen: Bokeh's row, whose box is
    a CSS flexbox, told to wrap. Panel's FlexBox does the same as a ReactiveHTML, 3.4 ms of
    server CPU more to make and 1 kB more of a page's first document, each."""
    params["stylesheets"] = [*params.get("stylesheets", []), WRAPS]
    return pn.Row(*objects, **params)


def on_screen(values) -> np.ndarray:
    """Plotted numbers as the browser gets them: float32, 7 digits (a thousandth of a pixel on
    any screen) in half the bytes of float64; the apexes and labels keep their own precision."""
    return np.asarray(values, dtype=np.float32)


# a room's inputs: a select's text and the player's buttons as large as the page's 20 px text
# (a select kept the browser's own 13 px, the player's buttons were 50 x 21 px; nine of 52 px
# fit its 520 px)
PROJECTED_INPUTS = (
    ":host select { font-size: 20px; }"
    " :host button { min-width: 52px; height: 40px; font-size: 20px; }"
)


PROJECTED_PLAYER_HEIGHT = 112  # (Panel's 80 px: the larger buttons ran under what follows)


def for_a_room(presentation: bool) -> list[str]:
    """The ``stylesheets`` of a select or a player: large for a room, else the widget's own."""
    return [PROJECTED_INPUTS] if presentation else []


def player_for_a_room(presentation: bool) -> dict:
    """A player's options: its buttons large for a room and the room to hold them."""
    if not presentation:
        return {}
    return {"stylesheets": for_a_room(True), "height": PROJECTED_PLAYER_HEIGHT}


def readable(fig, presentation: bool) -> None:
    """Font sizes of a Bokeh figure: for a screen, or for a room (tick labels >= 16 px, and
    lines, markers and labels drawn bold enough for the back of the room)."""
    ticks, labels, title = ("16pt", "18pt", "18pt") if presentation else ("10pt", "11pt", "12pt")
    for axis in fig.axis:
        axis.major_label_text_font_size = ticks
        axis.axis_label_text_font_size = labels
        # (16 pt labels on a plot half a projector wide ran into each other)
        if presentation and hasattr(axis.ticker, "desired_num_ticks"):
            axis.ticker.desired_num_ticks = 4
    if fig.title is not None:  # (a projected drop's heights have none)
        fig.title.text_font_size = title
    for legend in fig.legend:
        legend.label_text_font_size = ticks
    if presentation:
        # (not the balls' outlines: a thick ring would hide a small ball)
        marks = [r.glyph for r in fig.renderers if not hasattr(r.glyph, "radius")]
        # (not the time cursor, a vertical span: thick, it hid the curves it crossed)
        spans = [a for a in fig.center if isinstance(a, Span) and a.dimension == "width"]
        for mark in [*marks, *spans]:
            if isinstance(getattr(mark, "line_width", None), int | float):
                mark.line_width = max(mark.line_width, PROJECTOR_LINE_WIDTH)
            if isinstance(getattr(mark, "size", None), int | float):
                mark.size = max(mark.size, PROJECTOR_MARKER_SIZE)
        for labels_drawn in (a for a in fig.center if isinstance(a, LabelSet)):
            labels_drawn.text_font_size = ticks


def draw(fig, glyph: Glyph, source: ColumnDataSource) -> GlyphRenderer:
    """``glyph`` drawn from ``source`` on ``fig``, its looks when unselected or muted left to
    BokehJS ("auto"): one Bokeh model where ``fig.line(...)`` makes three. A page's opening
    costs the server about a millisecond a model (docs/performance.md, "A class at once"), and
    nothing here is selected or muted."""
    return fig.add_glyph(source, glyph)


def alert(text: str = "", **params) -> pn.pane.Alert:
    """A Panel alert with text dark enough to read (:data:`ALERT_CSS`)."""
    return pn.pane.Alert(text, stylesheets=[ALERT_CSS], **params)
