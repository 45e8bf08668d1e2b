"""Bokeh's messages to a page made with less work per message, the same for the browser.

A served slider move sends three messages (the server's answer to the move, the scene's patch,
the URL's rewrite), and each cost more in Bokeh 3.9 than its content needs:

- :func:`small_arrays_sent_inline`: every NumPy array in a message went as a binary buffer of
  its own, two more websocket frames each (a header, then the bytes) and a Python object per
  buffer at each end: a drop move's patch had five, two of them the apexes' two or three
  numbers (19 frames a move, 15 now). An array of at most :data:`INLINE_BYTES` goes inside the
  message's JSON as base64, as Bokeh itself writes every array into a standalone HTML file;
  BokehJS reads both forms.
- :func:`references_made_when_sent`: Bokeh's serializer made a reference object (``Ref``) for
  every model the page already has before each message, to look up the few the message names:
  3-4 % of a served move's samples (py-spy, drop and stack). A reference is made when the
  message meets its model.

tests/app/test_app_hooks.py checks that the messages carry what Bokeh's own would.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from bokeh.core.serialization import Serializer

# an array of at most this many bytes (128 float64) goes inside the message's JSON as base64:
# a third larger than the bytes, and two frames fewer
INLINE_BYTES = 1024


def small_arrays_sent_inline() -> None:
    """Arrays of at most :data:`INLINE_BYTES` encoded in the message's JSON (base64), not as a
    binary buffer of their own. Idempotent."""
    own = Serializer._encode_ndarray
    if getattr(own, "small_inline", False):
        return

    def _encode_ndarray(self: Serializer, obj: np.ndarray) -> Any:
        if not self._deferred or obj.nbytes > INLINE_BYTES:
            return own(self, obj)
        self._deferred = False
        try:
            return own(self, obj)
        finally:
            self._deferred = True

    _encode_ndarray.small_inline = True
    _encode_ndarray.__wrapped__ = own
    Serializer._encode_ndarray = _encode_ndarray


def references_made_when_sent() -> None:
    """A serializer's known models (``references``: those the page has) kept by identity, each
    one's reference made when the message meets it, not all of them before it starts.
    Idempotent."""
    own_init = Serializer.__init__
    if getattr(own_init, "lazy_references", False):
        return

    def init(self: Serializer, *, references: Any = frozenset(), **options: Any) -> None:
        own_init(self, **options)
        self._known = {id(model): model for model in references}

    def has_ref(self: Serializer, obj: Any) -> bool:
        return id(obj) in self._references or id(obj) in self._known

    def get_ref(self: Serializer, obj: Any) -> Any:
        ref = self._references.get(id(obj))
        if ref is None and id(obj) in self._known:
            ref = self._references[id(obj)] = obj.ref
        return ref

    def add_ref(self: Serializer, obj: Any, ref: Any) -> None:
        assert not self.has_ref(obj)
        self._references[id(obj)] = ref

    init.lazy_references = True
    init.__wrapped__ = own_init
    Serializer.__init__ = init
    Serializer.has_ref = has_ref
    Serializer.get_ref = get_ref
    Serializer.add_ref = add_ref
