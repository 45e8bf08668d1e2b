"""The server hooks (app/app_hooks.py): a page that closes while an update is being sent to it
is a client leaving, and the server log stays free of tracebacks."""

from __future__ import annotations

import types

import panel as pn
import panel.io.document
import panel.io.logging
import pytest
from tornado.websocket import WebSocketClosedError, WebSocketHandler


def _closing_connection():
    """A connection whose socket passes Panel's is-open check, then refuses the write: the tab
    closed in between."""
    socket = object.__new__(WebSocketHandler)
    socket.ws_connection = types.SimpleNamespace(is_closing=lambda: False)
    message = types.SimpleNamespace(
        header_json="{}", metadata_json="{}", content_json="{}", _buffers=[]
    )
    return types.SimpleNamespace(_socket=socket), message


def test_a_message_to_a_page_that_just_closed_is_dropped(monkeypatch):
    from app.app_hooks import drop_messages_to_closed_sockets

    def refuse(self, message, binary=False):
        raise WebSocketClosedError()

    monkeypatch.setattr(WebSocketHandler, "write_message", refuse)
    monkeypatch.setattr(
        panel.io.document, "dispatch_tornado", panel.io.document.dispatch_tornado
    )  # restored after the test
    connection, message = _closing_connection()
    with pytest.raises(WebSocketClosedError):  # Panel's own dispatch: the race this is about
        panel.io.document.dispatch_tornado(connection, msg=message)
    drop_messages_to_closed_sockets()
    drop_messages_to_closed_sockets()  # twice: still one wrapper
    assert panel.io.document.dispatch_tornado.__wrapped__.__name__ == "dispatch_tornado"
    assert panel.io.document.dispatch_tornado(connection, msg=message) == []


def test_a_socket_let_go_by_the_keep_alive_closes_quietly(monkeypatch):
    """Bokeh's keep-alive ping finds a page's socket closed and lets its session go; tornado's
    report of the close then came to a connection without a session: an AssertionError, a
    traceback in the server's log. Now it is logged as a client leaving."""
    from bokeh.server.connection import ServerConnection
    from bokeh.server.views.ws import WSHandler

    from app.app_hooks import sockets_let_go_once

    monkeypatch.setattr(WSHandler, "on_close", WSHandler.on_close)  # restored after the test
    lost = []
    handler = object.__new__(WSHandler)
    handler.close_code, handler.close_reason = 1001, None
    handler.application = types.SimpleNamespace(client_lost=lost.append)
    handler.connection = object.__new__(ServerConnection)
    handler.connection._session = None  # (let go by the keep-alive: client_lost)
    with pytest.raises(AssertionError):  # Bokeh's own: the race this is about
        WSHandler.on_close(handler)
    sockets_let_go_once()
    sockets_let_go_once()  # twice: still one wrapper
    assert WSHandler.on_close.__wrapped__.__name__ == "on_close"
    WSHandler.on_close(handler)
    assert handler.connection is None and lost == []


def test_a_write_task_failing_on_a_closed_page_is_a_warning_not_a_traceback(caplog):
    """The other half of the race: the writes Panel had started before the tab closed fail
    later, in tasks nobody awaits; asyncio logged them with a traceback."""
    import asyncio
    import gc
    import threading

    from app.app_hooks import closed_socket_handler

    passed_on = []
    loop = asyncio.new_event_loop()
    try:
        loop.set_exception_handler(
            closed_socket_handler(lambda loop, context: passed_on.append(context))
        )

        async def write_to_a_closed_page():
            raise WebSocketClosedError()

        async def other_failure():
            raise RuntimeError("a real bug")

        async def start_and_forget():
            loop.create_task(write_to_a_closed_page())
            loop.create_task(other_failure())
            await asyncio.sleep(0.01)

        def run() -> None:  # in a thread: Playwright's loop may be running in this one
            loop.run_until_complete(start_and_forget())
            gc.collect()  # the unretrieved tasks are reported when collected

        with caplog.at_level("WARNING", logger="bokeh.twoball"):
            thread = threading.Thread(target=run)
            thread.start()
            thread.join()
        assert "dropped" in caplog.text
        # a real failure still reaches the previous handler, with its exception
        assert [type(c.get("exception")) for c in passed_on] == [RuntimeError]
    finally:
        loop.close()


def test_a_server_process_accepts_one_waiting_connection_per_wake_up(monkeypatch):
    """Three connections wait on a listening socket; one wake-up of Tornado's accept handler
    takes one of them (it took all three before: app_hooks.accept_one_connection_at_a_time)."""
    import socket

    import tornado.netutil
    from tornado.ioloop import IOLoop

    from app import app_hooks

    monkeypatch.setattr(tornado.netutil, "_DEFAULT_BACKLOG", tornado.netutil._DEFAULT_BACKLOG)
    app_hooks.accept_one_connection_at_a_time()
    handlers = []
    loop = types.SimpleNamespace(add_handler=lambda fd, handler, events: handlers.append(handler))
    monkeypatch.setattr(IOLoop, "current", staticmethod(lambda instance=True: loop))
    with socket.socket() as listener:
        listener.bind(("127.0.0.1", 0))
        listener.listen(8)
        listener.setblocking(False)
        accepted = []
        tornado.netutil.add_accept_handler(listener, lambda conn, address: accepted.append(conn))
        clients = [socket.create_connection(listener.getsockname()) for _ in range(3)]
        try:
            (wake_up,) = handlers
            wake_up(listener, IOLoop.READ)
            assert len(accepted) == 1
            wake_up(listener, IOLoop.READ)
            assert len(accepted) == 2
        finally:
            for connection in [*clients, *accepted]:
                connection.close()


def _same_default(value, other) -> bool:
    """Equal defaults: models (built fresh for each default) of the same type, anything else
    equal, inside lists, tuples and dicts too."""
    from bokeh.core.has_props import HasProps

    if type(value) is not type(other):
        return False
    if isinstance(value, HasProps):
        return True
    if isinstance(value, (list, tuple)):
        return len(value) == len(other) and all(map(_same_default, value, other))
    if isinstance(value, dict):
        return value.keys() == other.keys() and all(
            _same_default(value[k], other[k]) for k in value
        )
    if value != value:  # NaN (DataRange1d's start and end)
        return other != other
    return value == other or (callable(value) and type(value) is type(other))


def test_cached_bokeh_defaults_equal_bokehs_own_for_every_model_class(monkeypatch):
    """app/bokeh_defaults.py answers each property's default from a per-class cache: every
    property of every model class (Bokeh's and Panel's) gets what Bokeh itself computes, asked
    twice (the second answer from the cache), and defaults that can change in place are still
    fresh per model."""
    import panel.models  # noqa: F401  (Panel's model classes registered beside Bokeh's)
    from bokeh.core.has_props import HasProps, is_abstract
    from bokeh.core.property.bases import Property
    from bokeh.core.property.descriptors import PropertyDescriptor
    from bokeh.model import Model
    from bokeh.models import ColumnDataSource, Slider

    from app.bokeh_defaults import cache_property_defaults

    def answers() -> dict:
        """Each concrete class's overridden defaults, and each property's default and whether
        it is kept per model, as the classes answer them now."""
        found = {}
        for cls in set(Model.model_class_reverse_map.values()):
            if is_abstract(cls):  # (never built; some of Bokeh's own answers raise)
                continue
            bare = object.__new__(cls)  # (has_unstable_default reads the class's overrides)
            found[cls] = (
                dict(cls._overridden_defaults()),
                {
                    name: (
                        cls.lookup(name).property.themed_default(cls, name, None),
                        cls.lookup(name).has_unstable_default(bare),
                    )
                    for name in cls.properties()
                },
            )
        return found

    own = answers()
    own_default = Property.themed_default
    for owner, name in [
        (Property, "themed_default"),
        (PropertyDescriptor, "has_unstable_default"),
        (HasProps, "_overridden_defaults"),
    ]:
        monkeypatch.setattr(owner, name, getattr(owner, name))  # restored after the test
    cache_property_defaults()
    cache_property_defaults()  # (idempotent: a second call wraps nothing twice)
    assert Property.themed_default.__wrapped__ is own_default
    for _ in range(2):  # (the second time from the cache)
        assert _same_default(answers(), own)
    assert sum(len(properties) for _, properties in own.values()) > 5000  # (~400 classes)
    # changeable defaults are never shared between models
    assert ColumnDataSource().data is not ColumnDataSource().data
    first, second = Slider(start=0, end=1, value=0), Slider(start=0, end=1, value=0)
    first.css_classes.append("moved")
    first.js_property_callbacks["value"] = []
    first.tags.append("moved")
    assert second.css_classes == [] and second.js_property_callbacks == {} and second.tags == []


def test_panel_works_out_a_design_only_for_new_stylesheets(monkeypatch):
    """app_hooks.design_resolved_for_new_stylesheets_only: a widget's change of value, and of
    its style sheets, give the same message as Panel's own ``_update_properties``; the design
    is worked out for the style sheets only."""
    import param
    from bokeh.document import Document
    from panel.reactive import Reactive
    from panel.theme.base import Design

    from app.app_hooks import design_resolved_for_new_stylesheets_only

    monkeypatch.setattr(Reactive, "_update_properties", Reactive._update_properties)
    panels_own = Reactive._update_properties
    slider = pn.widgets.FloatSlider(start=0, end=1, value=0.2, design=pn.theme.Material)
    doc = Document()
    slider.get_root(doc)

    def event(name: str, new) -> param.parameterized.Event:
        old = getattr(slider, name)
        return param.parameterized.Event(
            what="value", name=name, obj=slider, cls=type(slider), old=old, new=new,
            type="changed",
        )  # fmt: skip

    def sent(message: dict) -> dict:
        """The message, with the design's style sheets (a model each) by their address."""
        sheets = [getattr(sheet, "url", sheet) for sheet in message.get("stylesheets", [])]
        return message | ({"stylesheets": sheets} if sheets else {})

    changes = [event("value", 0.7), event("stylesheets", [":host { color: red; }"])]
    expected = [sent(panels_own(slider, change, doc=doc)) for change in changes]
    assert sum(s.endswith(".css") for s in expected[1]["stylesheets"]) >= 3  # the design's
    design_resolved_for_new_stylesheets_only()
    design_resolved_for_new_stylesheets_only()  # (idempotent)
    asked = []
    params = Design.params
    monkeypatch.setattr(Design, "params", lambda *a, **k: asked.append(1) or params(*a, **k))
    assert [sent(slider._update_properties(change, doc=doc)) for change in changes] == expected
    assert len(asked) == 1


def test_theme_values_read_directly_equal_bokehs_own(monkeypatch):
    """app/bokeh_defaults.themed_values_read_directly: a model with no theme, one a document
    theme applies to, and one whose theme was taken away again answer what Bokeh's own
    ``themed_values`` answers, and the themed model's properties take the theme's values."""
    from bokeh.core.has_props import HasProps
    from bokeh.document import Document
    from bokeh.models import Slider
    from bokeh.themes import Theme

    from app.bokeh_defaults import themed_values_read_directly

    monkeypatch.setattr(HasProps, "themed_values", HasProps.themed_values)  # restored after
    own = HasProps.themed_values
    theme = Theme(json={"attrs": {"Slider": {"bar_color": "#123456", "title": "themed"}}})
    plain = Slider(start=0, end=1, value=0)
    themed = Slider(start=0, end=1, value=0)
    unthemed = Slider(start=0, end=1, value=0)
    document = Document(theme=theme)
    document.add_root(themed)
    document.add_root(unthemed)
    document.remove_root(unthemed)  # (its theme taken away: Bokeh deletes the attribute)
    models = (plain, themed, unthemed)
    expected = [own(model) for model in models]
    assert expected[0] is None and expected[2] is None
    assert expected[1] == {"bar_color": "#123456", "title": "themed"}
    themed_values_read_directly()
    themed_values_read_directly()  # (idempotent)
    assert HasProps.themed_values.__wrapped__ is own
    assert [HasProps.themed_values(model) for model in models] == expected
    assert (themed.bar_color, themed.title) == ("#123456", "themed")
    assert (plain.bar_color, plain.title) == ("#e6e6e6", "")


def test_synced_parameters_listed_once_give_panels_own_values(monkeypatch):
    """app_hooks.synced_parameters_listed_once: every component of each scene's page (Panel's
    widgets, panes, layouts and the template's own) starts its model from the same values as
    with Panel's own ``Syncable._init_params``."""
    from bokeh.document import Document
    from panel.io.state import set_curdoc
    from panel.reactive import Syncable

    from app.app_hooks import synced_parameters_listed_once
    from app.explorer import Explorer
    from app.scenes import SCENES

    own = getattr(Syncable._init_params, "__wrapped__", Syncable._init_params)
    monkeypatch.setattr(Syncable, "_init_params", own)  # restored after the test
    synced_parameters_listed_once()
    synced_parameters_listed_once()  # (idempotent)
    assert Syncable._init_params.__wrapped__ is own
    compared = set()
    for scene in SCENES:
        document = Document()
        with set_curdoc(document):
            page = Explorer({"scene": scene, "step": "2" if scene == "drop" else "0"}).page()
            page.server_doc(document)
        components = [
            component for item in page.roots().values() for component in item.select(Syncable)
        ]
        for component in components:
            assert Syncable._init_params(component) == own(component), component
            compared.add(type(component).__name__)
    assert {"ReleasedSlider", "Markdown", "Column", "Tabs", "Button", "Bokeh", "Card"} <= compared


def test_the_loading_style_is_sent_once_per_page_with_panels_own_text(monkeypatch):
    """app_hooks.loading_style_sent_once_per_page: each model of each scene's page has the same
    style sheets, in the same order, as with Panel's own ``loading_css``, the spinner's text now
    one style sheet model shared by the page's components; and the first document is smaller."""
    import panel.reactive
    from bokeh.document import Document
    from bokeh.models import ImportedStyleSheet, InlineStyleSheet
    from panel.io.state import set_curdoc

    from app.app_hooks import loading_style_sent_once_per_page
    from app.explorer import Explorer
    from app.scenes import SCENES
    from benchmarks.app_open import first_message_bytes

    own = getattr(panel.reactive.loading_css, "__wrapped__", panel.reactive.loading_css)

    def page(scene: str) -> Document:
        document = Document()
        with set_curdoc(document):
            Explorer({"scene": scene}).page().server_doc(document)
        return document

    def style_sheets(document: Document) -> list:
        """Each model's style sheets as texts (a model's by its css or address), in order."""

        def text(sheet):
            if isinstance(sheet, InlineStyleSheet):
                return sheet.css
            return sheet.url if isinstance(sheet, ImportedStyleSheet) else sheet

        return sorted(
            (type(model).__name__, tuple(text(sheet) for sheet in model.stylesheets))
            for model in document.models
            if not isinstance(model, (InlineStyleSheet, ImportedStyleSheet))
            and hasattr(model, "stylesheets")
        )

    monkeypatch.setattr(panel.reactive, "loading_css", own)  # restored after the test
    before = {scene: page(scene) for scene in SCENES}
    loading_style_sent_once_per_page()
    loading_style_sent_once_per_page()  # (idempotent)
    assert panel.reactive.loading_css.__wrapped__ is own
    config = panel.config
    settings = (config.loading_spinner, config.loading_color, config.loading_max_height)
    spinner = own(*settings).strip()
    for scene in SCENES:
        after = page(scene)
        assert style_sheets(after) == style_sheets(before[scene]), scene
        inline = [m for m in after.models if isinstance(m, InlineStyleSheet)]
        shared = [m for m in inline if m.css.strip() == spinner]
        assert len(shared) == 1, scene
        users = [m for m in after.models if shared[0] in getattr(m, "stylesheets", ())]
        assert len(users) > 20, scene
        assert first_message_bytes(after) < first_message_bytes(before[scene]) - 5000, scene
    assert panel.reactive.loading_css(*settings) == own(*settings)  # (outside a page: the text)


def test_panel_makes_no_debug_record_its_handlers_would_drop(monkeypatch):
    """Panel's logger stood at DEBUG with a WARNING handler: every browser event made a log
    record only to drop it. At its handlers' level, a debug message makes none, while a
    warning still reaches the handler; a handler at DEBUG (Panel's admin page's) gets them."""
    import logging

    from app.app_hooks import panel_debug_messages_not_made

    logger = logging.getLogger("panel")
    monkeypatch.setattr(logger, "level", logging.DEBUG)  # (Panel's own setting, restored)
    # Panel's own handler alone (pytest adds its capturing handlers, at NOTSET, to the logger)
    monkeypatch.setattr(logger, "handlers", [panel.io.logging.panel_log_handler])
    made: list[str] = []
    make = logging.Logger.makeRecord

    def making(self, *args, **kwargs):
        made.append(self.name)
        return make(self, *args, **kwargs)

    monkeypatch.setattr(logging.Logger, "makeRecord", making)
    child = logging.getLogger("panel.reactive.Syncable")
    child.debug("Session %s received events", 1)
    assert len(made) == 1  # (as Panel ships: made, then dropped by its handler)
    panel_debug_messages_not_made()
    assert logger.level == panel.io.logging.panel_log_handler.level > logging.DEBUG
    child.debug("Session %s received events", 2)
    assert len(made) == 1
    child.warning("Session %s could not ...", 3)
    assert len(made) == 2
    handler = logging.NullHandler(logging.DEBUG)
    logger.addHandler(handler)
    try:
        panel_debug_messages_not_made()
        assert logger.level == logging.DEBUG
    finally:
        logger.removeHandler(handler)


def test_a_page_kinds_html_is_panels_own_with_its_resources_worked_out_once(monkeypatch):
    """app_hooks.page_resources_worked_out_once_per_page_kind: the HTML of a kept session's
    page, asked for again and again, is the HTML Panel's own functions give (its scripts, style
    sheets and variables; only the ids Bokeh makes for each rendering differ), for each scene
    and for a presented page; and the resources are worked out once per document."""
    import re

    import panel.io.server as server
    from bokeh.document import Document
    from bokeh.models import ImportedStyleSheet
    from bokeh.resources import Resources as BokehResources
    from panel.io.resources import Resources
    from panel.io.state import set_curdoc

    from app.app_hooks import page_resources_worked_out_once_per_page_kind
    from app.explorer import Explorer

    own_bundle = getattr(server.bundle_resources, "__wrapped__", server.bundle_resources)
    own_patch = getattr(server.patch_model_css, "__wrapped__", server.patch_model_css)
    counted = []

    def counting_bundle(*args, **kwargs):
        counted.append(args)
        return own_bundle(*args, **kwargs)

    monkeypatch.setattr(server, "bundle_resources", counting_bundle)  # restored after the test
    monkeypatch.setattr(server, "patch_model_css", own_patch)

    def kept_session(query: dict) -> types.SimpleNamespace:
        document = Document()
        with set_curdoc(document):
            Explorer(query).page().server_doc(document)
        return types.SimpleNamespace(document=document, token="kept")

    def html(session, token: str, mode: str = "server") -> str:
        document = session.document
        with set_curdoc(document):
            page = server.server_html_page_for_session(
                session,
                resources=Resources.from_bokeh(BokehResources(mode=mode)),
                title=document.title,
                token=token,
                template=document.template,
                template_variables=document.template_variables,
            )
        page = re.sub(r"[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}", "UUID", page)
        return re.sub(r"""(["'=])p\d+\b""", r"\1ID", page)

    def style_sheet_addresses(session) -> list[str]:
        return sorted(
            model.url for model in session.document.models if isinstance(model, ImportedStyleSheet)
        )

    queries = [{"scene": "drop"}, {"scene": "map"}, {"scene": "stack", "present": "1"}]
    expected, addresses = [], []
    for i, query in enumerate(queries):
        session = kept_session(query)
        expected.append([html(session, f"token-{i}", mode) for mode in ("server", "cdn")])
        addresses.append(style_sheet_addresses(session))
    page_resources_worked_out_once_per_page_kind()
    page_resources_worked_out_once_per_page_kind()  # (idempotent)
    assert server.bundle_resources.__wrapped__ is counting_bundle
    assert server.patch_model_css.__wrapped__ is own_patch
    assert "bokeh" in expected[0][0] and "<script" in expected[0][0]
    assert expected[0][0] != expected[0][1]  # (the two modes differ: each is checked)
    counted.clear()
    for i, query in enumerate(queries):
        session = kept_session(query)
        for _ in range(3):
            assert [html(session, f"token-{i}", mode) for mode in ("server", "cdn")] == expected[i]
        assert style_sheet_addresses(session) == addresses[i], query
    assert len(counted) == 2 * len(queries)  # once per document and mode, not per request


def test_small_arrays_go_inline_and_decode_as_bokehs_own_buffers(monkeypatch):
    """app/bokeh_messages.small_arrays_sent_inline: an array of at most INLINE_BYTES goes in
    the message's JSON, a larger one as a buffer; Bokeh's own reader gives back both arrays,
    values and dtypes, as it does from Bokeh's own message (every array a buffer)."""
    import numpy as np
    from bokeh.core.serialization import Deserializer, Serializer

    from app.bokeh_messages import INLINE_BYTES, small_arrays_sent_inline

    monkeypatch.setattr(Serializer, "_encode_ndarray", Serializer._encode_ndarray)  # restored
    rng = np.random.default_rng(3)
    data = {
        "apex_t": rng.random(3),
        "edge": rng.random(INLINE_BYTES // 8),  # (exactly the limit: inline)
        "counts": np.arange(5, dtype=np.int32),
        "curve": rng.random(INLINE_BYTES // 8 + 1),  # (one more: a buffer)
        "image": rng.random((40, 30)).astype(np.float32),
    }
    own = Serializer().serialize(data)
    assert len(own.buffers) == len(data)
    small_arrays_sent_inline()
    small_arrays_sent_inline()  # (idempotent)
    sent = Serializer().serialize(data)
    assert len(sent.buffers) == 2  # the curve and the image
    assert all(isinstance(sent.content["entries"][i][1]["array"]["data"], str) for i in (0, 1, 2))
    for message in (own, sent):
        decoded = Deserializer().deserialize(message)
        for name, array in data.items():
            assert decoded[name].dtype == array.dtype and decoded[name].shape == array.shape
            np.testing.assert_array_equal(decoded[name], array)
    # a serializer asked for no buffers (a standalone file) still gets none
    assert Serializer(deferred=False).serialize(data).buffers == []


def test_references_made_when_sent_give_bokehs_own_patch(monkeypatch):
    """app/bokeh_messages.references_made_when_sent: a patch that changes a model the page has,
    adds a new one and refers to an old one from it is Bokeh's own message, and leaves the same
    models counted as new (not yet sent) in the document."""
    import json

    from bokeh.core.serialization import Serializer
    from bokeh.document import Document
    from bokeh.models import ColumnDataSource, Range1d, Title
    from bokeh.plotting import figure
    from bokeh.protocol import Protocol

    from app.bokeh_messages import references_made_when_sent

    for name in ("__init__", "has_ref", "get_ref", "add_ref"):
        monkeypatch.setattr(Serializer, name, getattr(Serializer, name))  # restored after
    document = Document()
    plot = figure(x_range=Range1d(0, 1))
    source = ColumnDataSource({"x": [0.0, 1.0], "y": [1.0, 2.0]})
    plot.line("x", "y", source=source)
    document.add_root(plot)
    document.models.flush_synced()  # (the page has them all)
    events = []
    document.on_change(lambda event: events.append(event))
    plot.x_range.end = 2.0
    source.data = {"x": [0.0, 2.0], "y": [3.0, 4.0]}
    plot.title = Title(text="new")  # a new model
    plot.extra_y_ranges = {"right": plot.x_range}  # an old one named again
    new_before = set(document.models._new_models)
    assert new_before  # (the title)

    def patch() -> tuple[dict, set]:
        document.models._new_models = set(new_before)
        message = Protocol().create("PATCH-DOC", events)
        return json.loads(message.content_json), set(document.models._new_models)

    own = patch()
    references_made_when_sent()
    references_made_when_sent()  # (idempotent)
    assert Serializer.__init__.__wrapped__ is not None
    assert patch() == own
    assert plot.x_range.id in json.dumps(own[0])


def test_read_only_lifted_where_set_behaves_as_panels_own(monkeypatch):
    """app_hooks.read_only_lifted_where_set: a browser's change to a slider (value and the
    constant value_throttled) is applied, value_throttled is constant again after, and a
    watcher of a parameter's ``constant`` sees the same events as under Panel's own
    ``edit_readonly``."""
    import panel.reactive
    import panel.widgets.slider
    import param

    from app.app_hooks import read_only_lifted_where_set

    monkeypatch.setattr(panel.reactive, "edit_readonly", panel.reactive.edit_readonly)
    monkeypatch.setattr(panel.widgets.slider, "edit_readonly", panel.widgets.slider.edit_readonly)

    class Watched(param.Parameterized):
        fixed = param.Number(1.0, constant=True)
        free = param.Number(2.0)
        free_watched = param.Number(3.0)
        only_read = param.Number(4.0, readonly=True)

    def run() -> tuple:
        slider = pn.widgets.FloatSlider(start=0, end=1, value=0.5)
        slider._process_events({"value": 0.25, "value_throttled": 0.25})
        seen = []
        watched = Watched()
        watched.param.watch(seen.append, ["free_watched", "fixed"], what="constant")
        with panel.reactive.edit_readonly(watched):
            watched.fixed, watched.only_read, watched.free = 5.0, 6.0, 7.0
        events = [(e.name, e.what, e.old, e.new) for e in seen]
        constant = {p.name: (p.constant, p.readonly) for p in watched.param.objects().values()}
        with pytest.raises(TypeError):
            watched.fixed = 8.0
        throttled = slider.param["value_throttled"].constant
        return (
            slider.value,
            slider.value_throttled,
            throttled,
            {k: v for k, v in watched.param.values().items() if k != "name"},
            events,
            constant,
        )

    own = run()
    read_only_lifted_where_set()
    read_only_lifted_where_set()  # (idempotent)
    assert panel.reactive.edit_readonly.where_set
    assert run() == own
    assert own[:2] == (0.25, 0.25) and own[4]  # (a constant watcher saw the lift)
