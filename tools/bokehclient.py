"""A page as the server sees it, without a browser: an HTTP request for the page, then a
websocket that speaks Bokeh's protocol (what BokehJS sends and receives), on loopback.

A :class:`PageClient` opens a session as a browser does (GET the page, read its session token,
connect the websocket, pull the document, say it is drawn), finds a slider by its title and
moves it as a browser does on release (one PATCH-DOC setting ``value`` and
``value_throttled``), and records when each message from the server arrives. No rendering:
many sessions fit in one process. Used by benchmarks/app_load.py and the app's tests
(tests/app/test_app_serve.py).
"""

from __future__ import annotations

import asyncio
import itertools
import json
import re
import socket
import struct
import time
from dataclasses import dataclass, field

from tornado.httpclient import AsyncHTTPClient, HTTPRequest
from tornado.websocket import websocket_connect

TOKEN = re.compile(r'"token":\s*"([^"]+)"')
_ids = itertools.count(1)
TCP_INFO_BYTES_RECEIVED = 128  # offset of tcpi_bytes_received in struct tcp_info (linux/tcp.h)


@dataclass
class Patch:
    """A PATCH-DOC from the server: when it arrived (time.monotonic), the ids of the models it
    changes and its events."""

    arrived: float
    models: set[str]
    events: list[dict]


def models_of(document: dict) -> dict[str, dict]:
    """Every model of a pulled document by id (Bokeh 3's serialisation: objects with ``id``,
    ``name`` and ``attributes``, nested anywhere)."""
    found: dict[str, dict] = {}

    def walk(node: object) -> None:
        if isinstance(node, dict):
            if node.get("type") == "object" and "id" in node and "name" in node:
                found.setdefault(node["id"], node)
            for value in node.values():
                walk(value)
        elif isinstance(node, list):
            for value in node:
                walk(value)

    walk(document)
    return found


@dataclass
class PageClient:
    """One browser page of the app at ``url`` (e.g. http://127.0.0.1:5006/app?scene=drop)."""

    url: str
    opened: float = float("nan")  # seconds from the GET to the document pulled
    started: float = float("nan")  # time.monotonic() of the GET
    document_bytes: int = 0  # the pulled document: its JSON and its binary buffers
    document_wire_bytes: int = 0  # what the page received for it on the socket (compressed)
    models: dict[str, dict] = field(default_factory=dict)
    patches: list[Patch] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)
    _socket: object = None
    _replies: asyncio.Queue | None = None
    _reader: asyncio.Task | None = None

    async def open(self, timeout: float = 60.0) -> None:
        """GET the page, connect its websocket and pull the document."""
        start = self.started = time.monotonic()
        response = await AsyncHTTPClient().fetch(self.url, request_timeout=timeout)
        token = TOKEN.search(response.body.decode()).group(1)
        base, _, _query = self.url.partition("?")
        host = base.split("/")[2]
        request = HTTPRequest(
            base.replace("http://", "ws://").rstrip("/") + "/ws",
            headers={"Origin": f"http://{host}"},
            request_timeout=timeout,
        )
        self._socket = await websocket_connect(
            request,
            subprotocols=["bokeh", token],
            compression_options={},  # as browsers offer
        )
        # a message is several frames: without TCP_NODELAY each frame after the first waits for
        # the server's delayed ACK (~40 ms); browsers send theirs at once
        self._socket.stream.set_nodelay(True)
        self._replies = asyncio.Queue()
        self._reader = asyncio.ensure_future(self._read())
        await self._expect("ACK", timeout)
        before = self.received()
        await self._send("PULL-DOC-REQ", {})
        reply = await self._expect("PULL-DOC-REPLY", timeout)
        self.document_wire_bytes = self.received() - before
        self.models = models_of(reply["doc"])
        self.opened = time.monotonic() - start
        # what BokehJS sends once the page is drawn (Panel's pn.state.onload callbacks run then)
        values = {"type": "map", "entries": []}
        ready = {"type": "event", "name": "document_ready", "values": values}
        event = {"kind": "MessageSent", "msg_type": "bokeh_event", "msg_data": ready}
        await self._send("PATCH-DOC", {"events": [event]})

    async def _send(self, msgtype: str, content: dict) -> str:
        msgid = str(next(_ids))
        for part in ({"msgid": msgid, "msgtype": msgtype}, {}, content):
            await self._socket.write_message(json.dumps(part))
        return msgid

    async def _read(self) -> None:
        """Read messages (header, metadata, content, then a header and a body per buffer)."""
        while True:
            header = await self._socket.read_message()
            if header is None:
                return
            header = json.loads(header)
            await self._socket.read_message()  # metadata
            text = await self._socket.read_message()
            content = json.loads(text)
            buffers = 0
            for _ in range(header.get("num_buffers", 0)):
                await self._socket.read_message()
                buffers += len(await self._socket.read_message())
            arrived = time.monotonic()
            if header["msgtype"] == "PATCH-DOC":
                events = content.get("events", [])
                models = {e["model"]["id"] for e in events if isinstance(e.get("model"), dict)}
                self.patches.append(Patch(arrived, models, events))
            elif header["msgtype"] == "ERROR":
                self.errors.append(content.get("text", str(content)))
            else:
                if header["msgtype"] == "PULL-DOC-REPLY":
                    self.document_bytes = len(text) + buffers
                await self._replies.put((header["msgtype"], content))

    async def _expect(self, msgtype: str, timeout: float) -> dict:
        while True:
            kind, content = await asyncio.wait_for(self._replies.get(), timeout)
            if kind == msgtype:
                return content

    def complete(self) -> float:
        """Seconds from the GET to the last message received so far (a page's scene follows its
        document once the page is in the browser, app/main.py)."""
        last = max((patch.arrived for patch in self.patches), default=self.started + self.opened)
        return max(last - self.started, self.opened)

    def received(self) -> int:
        """Bytes received on the websocket's TCP connection so far (Linux TCP_INFO's
        tcpi_bytes_received): what crossed the network, after compression."""
        raw = self._socket.stream.socket.getsockopt(socket.IPPROTO_TCP, socket.TCP_INFO, 256)
        return struct.unpack_from("<Q", raw, TCP_INFO_BYTES_RECEIVED)[0]

    def find(self, name: str, **attributes: object) -> str:
        """The id of the one model of type ``name`` whose attributes include ``attributes``."""
        ids = [
            model_id
            for model_id, model in self.models.items()
            if model["name"] == name
            and all(model.get("attributes", {}).get(k) == v for k, v in attributes.items())
        ]
        if len(ids) != 1:
            raise LookupError(f"{len(ids)} {name} models with {attributes}")
        return ids[0]

    def slider(self, title: str) -> str:
        """The id of the slider titled ``title`` (e.g. "eps (restitution)")."""
        return self.find("Slider", title=title)

    async def move(self, slider_id: str, value: float) -> float:
        """Move a slider as a browser does when it is released: one message setting ``value``
        and ``value_throttled`` (BokehJS's slider sets both in one ``setv``, which it sends as
        one PATCH-DOC of two events); returns when it was sent."""
        return await self.set(slider_id, {"value": value, "value_throttled": value})

    async def set(self, model_id: str, changes: dict[str, object]) -> float:
        """Change attributes of a model in one message, as the browser does (e.g. a player's
        ``value`` at each frame); returns when it was sent."""
        events = [
            {"kind": "ModelChanged", "model": {"id": model_id}, "attr": attr, "new": value}
            for attr, value in changes.items()
        ]
        await self._send("PATCH-DOC", {"events": events})
        return time.monotonic()

    def value(self, model_id: str, attr: str) -> object:
        """The last value the server sent for a model's attribute (or the pulled one)."""
        for patch in reversed(self.patches):
            for event in reversed(patch.events):
                if event.get("model", {}).get("id") == model_id and event.get("attr") == attr:
                    return event.get("new")
        return self.models[model_id]["attributes"].get(attr)

    async def close(self) -> None:
        if self._socket is not None:
            self._socket.close()
        if self._reader is not None:
            self._reader.cancel()
