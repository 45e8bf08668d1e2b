"""The server hooks (app/app_hooks.py): a page that closes while an update is being sent to it
is a client leaving, and the server log stays free of tracebacks."""

from __future__ import annotations

import types

import panel.io.document
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
