"""Server hooks of the directory app: the solver must never keep a page waiting for numba.

At start-up the kernels' Python functions stand in for them (same results, a drop in ~25 ms)
while another process compiles them (about 3 minutes on a new machine or CPU, ~2 s from the
disk cache); the machine code takes over as it comes, the two-ball solver's in 1-2 minutes
(:func:`twoball.warmup.compile_in_background`). The map cube is
opened once per server. A page closed while an update is being sent to it is a client leaving,
not an error (:func:`drop_messages_to_closed_sockets`).
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import gc
import logging
import sys
import time
import weakref

import panel
import panel.io.document
import panel.io.server
import panel.reactive
import panel.widgets.slider
import tornado.netutil
from bokeh.models import InlineStyleSheet
from bokeh.server.views.ws import WSHandler
from bokeh.settings import settings as bokeh_settings
from panel.io.state import state as panel_state
from panel.reactive import Reactive, Syncable
from tornado.ioloop import IOLoop
from tornado.websocket import WebSocketClosedError

from twoball import warmup

from .accuracy import measure_ahead
from .bokeh_defaults import cache_property_defaults, themed_values_read_directly
from .bokeh_messages import references_made_when_sent, small_arrays_sent_inline
from .map_slices import map_cube
from .scenes import SCENE_REGISTRY

# under bokeh's logger, which `panel serve --log-level` shows (info by default)
log = logging.getLogger("bokeh.twoball")
# Panel parses every query value that looks like an integer with int(), which Python refuses
# beyond 4300 digits (a traceback, and a page without its URL kept in step). Tornado refuses a
# request whose headers exceed 64 kB, so no value has more digits than this, and int() of it
# costs milliseconds.
QUERY_DIGITS = 70_000


def page_kind(request) -> tuple[str, bool]:
    """What the HTML of a page depends on, for ``--reuse-sessions`` (``twoball serve``): its
    path and presentation mode (the template's style sheet). Every other query value is read
    when the page's session is built."""
    present = request.arguments.get("present", [b""])[-1].decode(errors="replace")
    return request.path, present in ("1", "true", "yes")


def drop_messages_to_closed_sockets() -> None:
    """Panel 1.9 checks that a socket is open, then writes a message's parts one by one; a tab
    closed between the two makes the write raise WebSocketClosedError inside a task nobody
    awaits, and the server logs a traceback ("Task exception was never retrieved"). Panel's
    own handling of that error, when it comes later, is a warning and the message dropped
    (panel.io.document._run_write_futures): do the same here. Idempotent.

    A patch of Panel's private ``dispatch_tornado``, kept with its minimal reproducer:
    tests/app/test_app_hooks.py::test_a_message_to_a_page_that_just_closed_is_dropped first
    shows Panel's own function raising on a socket that closes between its check and its
    writes. When a Panel release catches that itself, that first assertion fails, and this
    patch is to be removed (the cause is in Panel; no setting of ours avoids the race)."""
    dispatch = panel.io.document.dispatch_tornado
    if getattr(dispatch, "drops_closed", False):
        return

    @functools.wraps(dispatch)
    def dispatch_to_open_sockets(*args, **kwargs):
        try:
            return dispatch(*args, **kwargs)
        except WebSocketClosedError:
            log.warning("a page closed while a message to it was being sent; dropped")
            return []

    dispatch_to_open_sockets.drops_closed = True
    panel.io.document.dispatch_tornado = dispatch_to_open_sockets


def sockets_let_go_once() -> None:
    """Bokeh 3.9's keep-alive ping, finding a page's socket closed, lets the page's session go
    (``client_lost`` detaches it from its connection); when tornado reports the close later,
    ``WSHandler.on_close`` asks that connection for its session, asserts that it has one, and
    the server logged a traceback. A page closed while the server was busy for seconds does it
    (a fresh clone's test run under load: every later test then failed on the log). Such a
    close is a client leaving that was already let go: logged, nothing more. Idempotent.

    A patch of Bokeh's ``WSHandler.on_close``, kept with its reproducer:
    tests/app/test_app_hooks.py::test_a_socket_let_go_by_the_keep_alive_closes_quietly first
    shows Bokeh's own raising; when a Bokeh release checks for it, that assertion fails, and
    this patch is to be removed."""
    on_close = WSHandler.on_close
    if getattr(on_close, "let_go_once", False):
        return

    @functools.wraps(on_close)
    def on_close_once(self) -> None:
        if self.connection is not None and self.connection._session is None:
            log.info("a page's socket closed after its session was let go")
            self.connection = None  # (let go already: Bokeh's own close has nothing to do)
        on_close(self)

    on_close_once.let_go_once = True
    WSHandler.on_close = on_close_once


def closed_socket_handler(previous):
    """An exception handler for the server's event loop: a write that failed because its page
    had closed is a client leaving, logged as a warning; anything else goes to ``previous`` (the
    loop's default handler if None).

    When a tab closes halfway through a message, Panel's dispatch has already started the
    writes of the message's first parts as tasks; the next write raises (dropped above) and
    those tasks, which nobody awaits now, fail with WebSocketClosedError and asyncio logged
    "Task exception was never retrieved" with a traceback (in about 1 of 3 first starts, whose
    test opens and closes pages every few seconds)."""

    def handle(loop: asyncio.AbstractEventLoop, context: dict) -> None:
        if isinstance(context.get("exception"), WebSocketClosedError):
            log.warning("a page closed while a message to it was being sent; dropped")
        elif previous is not None:
            previous(loop, context)
        else:
            loop.default_exception_handler(context)

    return handle


def on_server_loaded(server_context) -> None:
    """Serve at once on the Python kernels, compile in the background; open the map cube; drop
    messages to pages that have closed; Bokeh's property defaults worked out once per class."""
    sys.set_int_max_str_digits(QUERY_DIGITS)
    panel.config.session_key_func = page_kind
    bokeh_as_served()
    drop_messages_to_closed_sockets()
    sockets_let_go_once()
    loop = IOLoop.current().asyncio_loop
    loop.set_exception_handler(closed_socket_handler(loop.get_exception_handler()))
    started = time.monotonic()

    def staged(stage: str) -> None:
        log.info("%s kernels in use after %.1f s", stage, time.monotonic() - started)
        if stage == "two-ball":  # (the accuracy's methods; in the compiler's thread)
            measure_ahead()

    def compiled() -> None:
        log.info("compiled kernels in use after %.1f s", time.monotonic() - started)

    warmup.compile_in_background(done=compiled, staged=staged)
    for entry in SCENE_REGISTRY.values():  # imported now, not by the first page to visit one
        entry.viewer_class()
    try:
        map_cube()
    except (OSError, ValueError) as error:  # the map scene shows this too
        log.warning("the map cube could not be opened: %s", error)
    exempt_the_server_from_collection()
    accept_one_connection_at_a_time()
    page_resources_worked_out_once_per_page_kind()


def bokeh_as_served() -> None:
    """Bokeh without the checks and recomputations that are the same for every session (the
    benchmarks of a page's cost apply this too)."""
    # Bokeh checks every new session's document for mistakes of construction (a renderer
    # without a glyph, a layout without children), about 7 % of a page's opening cost; the
    # pages are the same for every session, and tests/app/test_app_state.py checks each scene's
    # document once (test_every_scene_builds_a_valid_document)
    bokeh_settings.perform_document_validation.set_value(False)
    # its "error diagnostics" check each callback's signature as it is registered (Panel's
    # own, about 200 a page) and answer each missing attribute with close matches from difflib
    # (Panel asks hasattr of models often): 4-6 % of a page's opening cost (app_open.py, two
    # runs alternating, drop 164/174 -> 158/163 ms); a mistake of ours still raises, its message
    # without the suggestions
    bokeh_settings.perform_error_diagnostics.set_value(False)
    cache_property_defaults()
    themed_values_read_directly()
    design_resolved_for_new_stylesheets_only()
    synced_parameters_listed_once()
    loading_style_sent_once_per_page()
    panel_debug_messages_not_made()
    small_arrays_sent_inline()
    read_only_lifted_where_set()
    references_made_when_sent()


def panel_debug_messages_not_made() -> None:
    """Panel's logger at the level of its handlers, not at DEBUG.

    Panel sets its logger to DEBUG and filters in its handler (WARNING unless
    ``PANEL_LOG_LEVEL`` says otherwise), so every debug message of every session (one for each
    event a browser sends) made a log record that the handler then dropped: 6.6 % of a served
    slider move's server CPU (py-spy, 200 moves of the drop). A handler added later (Panel's
    admin page, ``--admin``) gets what it asks for: the logger is then set to the lowest level
    of any handler again. Idempotent."""
    logger = logging.getLogger("panel")
    levels = [handler.level for handler in logger.handlers] or [logging.WARNING]
    if panel.config.admin:  # (its log tab shows debug messages)
        levels.append(logging.DEBUG)
    logger.setLevel(min(levels) or logging.DEBUG)  # (a handler at NOTSET takes everything)


def design_resolved_for_new_stylesheets_only() -> None:
    """Panel works out a component's design (its theme's style sheets, found on disk through
    param's path resolution) at every change of any of its properties, and uses the answer only
    when the change is to ``stylesheets``: a sixth of a served slider move (py-spy, 200 moves of
    the drop). Worked out only then; the message sent is the same (tests/app/test_app_hooks.py
    compares it with Panel's own for both kinds of change). Idempotent.

    A patch of Panel 1.9's ``Reactive._update_properties``, whose body this repeats but for the
    order of two lines."""
    if getattr(Reactive._update_properties, "design_when_needed", False):
        return

    def _update_properties(self, *events, doc):
        changes = {event.name: event.new for event in events}
        if "stylesheets" in changes and self._design:
            params, _ = self._design.params(self, doc)
            if "stylesheets" in params:
                changes["stylesheets"] = params["stylesheets"] + changes["stylesheets"]
        return self._process_param_change(changes)

    _update_properties.design_when_needed = True
    Reactive._update_properties = _update_properties


def synced_parameters_listed_once() -> None:
    """Panel lists a component's synced parameters once, not once per parameter, when it
    makes the component's first model.

    Panel 1.9's ``Syncable._init_params`` tests each of a component's parameters (about 40)
    for membership in ``_synced_params``, a property that builds the list anew at each test:
    some 30 000 of a page's 650 000 Python calls (benchmarks/app_open.py). The values are the
    same (tests/app/test_app_hooks.py compares them with Panel's for every component of each
    scene's page). Subclasses that override ``_init_params`` call this one through
    ``super()`` or replace it, as before. Idempotent."""
    if getattr(Syncable._init_params, "listed_once", False):
        return
    panels_own = Syncable._init_params

    def _init_params(self) -> dict:
        synced = set(self._synced_params)
        return {
            name: value
            for name in self.param
            if name in synced and (value := getattr(self, name)) is not None
        }

    _init_params.listed_once = True
    _init_params.__wrapped__ = panels_own
    Syncable._init_params = _init_params


def loading_style_sent_once_per_page() -> None:
    """Panel's style sheet for a component's loading spinner goes to the browser once per page,
    a style sheet model each component refers to, not its text inline in every component.

    Panel 1.9 puts the same 250 characters (``panel.io.resources.loading_css``) into each
    component's ``stylesheets``; a page's first document carried them some 40 times, 10 kB of
    its 48 (benchmarks/app_open.py: drop 48.0 -> 38.1 kB, stack 53.3 -> 42.4 kB). The
    model is kept in Panel's own per-page cache of style sheets (``state._stylesheets``, where
    it keeps the design's), and goes with the page. Outside a page (no current document) the
    text, as before. tests/app/test_app_hooks.py checks that every component of each scene's
    page has the same style sheets as with Panel's own, one shared model in place of the text.
    Idempotent."""
    own = panel.reactive.loading_css
    if getattr(own, "shared_per_page", False):
        return

    @functools.wraps(own)
    def loading_css(*args, **kwargs):
        css = own(*args, **kwargs)
        document = panel_state.curdoc
        if document is None:
            return css
        cache = panel_state._stylesheets.get(document)
        if cache is None:
            cache = panel_state._stylesheets[document] = {}
        sheet = cache.get(css)
        if sheet is None:
            sheet = cache[css] = InlineStyleSheet(css=css)
        return sheet

    loading_css.shared_per_page = True
    panel.reactive.loading_css = loading_css


def read_only_lifted_where_set() -> None:
    """Panel lifts ``readonly`` and ``constant`` for the time of a browser's change only on the
    parameters that have one set (or a watcher of either), not on all of a widget's.

    Panel 1.9's ``edit_readonly`` sets both to False on each of a widget's parameters (a
    slider's 33) and back, each a call of param's attribute machinery: 0.40 ms at every event
    a browser sends, 5 % of a served stack move's samples (py-spy). For a parameter with
    neither set and no watcher of them, those writes change nothing (param's ``_on_set`` acts
    on ``path`` alone), so they are skipped: 0.15 ms. Patched where a browser's events are
    applied (``panel.reactive``, ``panel.widgets.slider``); tests/app/test_app_hooks.py checks
    that a constant parameter is writable inside and constant again after, as with Panel's.
    Idempotent."""
    if getattr(panel.reactive.edit_readonly, "where_set", False):
        return

    @contextlib.contextmanager
    def edit_readonly(parameterized):
        touched = [
            (parameter, parameter.readonly, parameter.constant)
            for parameter in parameterized.param.objects("existing").values()
            if parameter.readonly
            or parameter.constant
            or {"readonly", "constant"} & set(parameter.watchers)
        ]
        for parameter, _, _ in touched:
            parameter.readonly = False
            parameter.constant = False
        try:
            yield
        finally:
            for parameter, readonly, constant in touched:
                parameter.readonly = readonly
                parameter.constant = constant

    edit_readonly.where_set = True
    panel.reactive.edit_readonly = edit_readonly
    panel.widgets.slider.edit_readonly = edit_readonly


def page_resources_worked_out_once_per_page_kind() -> None:
    """A page's HTML lists the same scripts and style sheets for every request of its kind:
    work them out once per kept session, not once per request.

    ``twoball serve`` answers a page's HTTP request from a session kept per page kind
    (``--reuse-sessions``, :func:`page_kind`), and Panel 1.9 then, for every request, works out
    that session's resource bundle (``bundle_resources``: its extensions, their files, whether
    MathJax is needed) and walks all its models to point their style sheets at the server
    (``patch_model_css``), about 5 and 4 ms, for the same answer each time. Both are done once
    per kept session's document (and resources, path), then reused; the token and the page's
    own variables are still rendered per request. tests/app/test_app_hooks.py compares the
    HTML with Panel's own. Idempotent."""
    server = panel.io.server
    if getattr(server.bundle_resources, "once_per_page", False):
        return
    bundle_resources, patch_model_css = server.bundle_resources, server.patch_model_css
    bundles: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
    patched: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()

    @functools.wraps(bundle_resources)
    def bundle_once(roots, resources, *args, **kwargs):
        document = panel_state.curdoc
        if args or kwargs or document is None:
            return bundle_resources(roots, resources, *args, **kwargs)
        key = (
            resources.mode, resources.root_url, resources.absolute, panel_state.rel_path,
            tuple(root.id for root in roots),
        )  # fmt: skip
        known = bundles.setdefault(document, {})
        if key not in known:
            known[key] = bundle_resources(roots, resources)
        return known[key]

    @functools.wraps(patch_model_css)
    def patch_once(root, dist_url):
        document = root.document
        if document is None:
            return patch_model_css(root, dist_url)
        done = patched.setdefault(document, set())
        if (root.id, dist_url) not in done:
            patch_model_css(root, dist_url)
            done.add((root.id, dist_url))
        return None

    bundle_once.once_per_page = True
    server.bundle_resources, server.patch_model_css = bundle_once, patch_once


def accept_one_connection_at_a_time() -> None:
    """Each server process takes one new connection per wake-up, so that a class's pages are
    shared among the processes (``twoball serve --num-procs``) by which of them is free.

    The processes share one listening socket, and Tornado's accept handler takes up to 128
    waiting connections each time it wakes: the first process to wake took most of a burst
    and built those sessions alone while the other idled. Measured with 30 pages opened at once
    on two processes (server CPU of each, three bursts): 7.5 / 3.3 s, 9.7 / 1.7 s, 7.9 / 4.0 s
    before; 5.9 / 5.9 s, 5.9 / 6.0 s, 5.9 / 5.8 s after. A process busy building a session
    is not waiting on the socket, so the next connection goes to one that is.

    Tornado reads the count from its private ``netutil._DEFAULT_BACKLOG`` at each wake-up (the
    listening socket's own backlog was fixed when it was bound, before this runs);
    tests/app/test_app_hooks.py checks that one wake-up now accepts one connection, and fails
    if a Tornado release reads it elsewhere."""
    tornado.netutil._DEFAULT_BACKLOG = 1


def exempt_the_server_from_collection() -> None:
    """Leave the objects the server holds for ever (the imported libraries, the map cube: some
    350 000) out of Python's cycle collection, before any session exists.

    Building a session allocates enough to start a full collection every few sessions, and
    Panel runs one after sessions close; each walked every object of the process, about 100 ms
    on 2 cores: a sixth of a page's opening cost, and seconds when a class closed its tabs.
    Objects of the sessions themselves are collected as before (``gc.freeze``)."""
    gc.collect()
    gc.freeze()
