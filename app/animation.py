"""The animations of the drop and Stack scenes, played in the browser.

A scene sends its frames once per drop: a ColumnDataSource with each frame's time (as shown),
caption, and each ball's centre ``y<b>`` and radius ``r<b>`` as drawn (ball ``b`` from the
bottom). The player's frame number picks one in the browser (:data:`FRAME_JS`), and the balls,
the time cursor on the heights and the caption change there alone (Bokeh's ``setv(...,
{sync: false})``: nothing is sent back). Drawn on the server, a frame cost 3 ms of server CPU,
71 ms a second for each student playing, so a class pressing play at once saturated two cores
(docs/performance.md, "A class at once"); now the server only hears the frame number, which
Panel's player syncs.
"""

from __future__ import annotations

import numpy as np
import panel as pn
from bokeh.models import ColumnDataSource, CustomJS

# args: frames, balls (the drawn balls' source), cursor (a Span), title (the stage's Title),
# colors (one a ball), trail (a source, or null) and trail_lines (its renderers), player (the
# Player's model, set when it is made)
FRAME_JS = """
const data = frames.data;
const count = data.t.length;
if (count == 0 || player == null) return;
const at = Math.max(0, Math.min(player.value, count - 1));
const y = [], r = [];
for (let b = 0; b < colors.length; b++) {
  y.push(data["y" + b][at]);
  r.push(data["r" + b][at]);
}
balls.setv({data: {x: colors.map(() => 0), y: y, r: r, color: colors}}, {sync: false});
cursor.setv({location: data.t[at]}, {sync: false});
title.setv({text: data.caption[at]}, {sync: false});
if (trail != null && trail_lines.length > 0 && trail_lines[0].visible) {
  const shown = {t: Array.from(data.t.slice(0, at + 1))};
  for (let b = 0; b < colors.length; b++) {
    const centres = data["y" + b], radii = data["r" + b];
    shown["top" + b] = shown.t.map((_, i) => centres[i] + radii[i]);
  }
  trail.setv({data: shown}, {sync: false});
}
"""


def frame_callback(**args) -> CustomJS:
    """The :data:`FRAME_JS` callback of an animation (its args as :data:`FRAME_JS` says)."""
    return CustomJS(args={"player": None, "trail": None, "trail_lines": [], **args}, code=FRAME_JS)


class FramePlayer(pn.widgets.Player):
    """Panel's player, each of whose frames is drawn in the browser by ``on_frame`` (a
    :func:`frame_callback`), given its model when the model is made."""

    def __init__(self, on_frame: CustomJS, **params):
        super().__init__(**params)
        self._on_frame = on_frame

    def _get_model(self, doc, root=None, parent=None, comm=None):
        model = super()._get_model(doc, root, parent, comm)
        self._on_frame.args = {**self._on_frame.args, "player": model}
        model.js_on_change("value", self._on_frame)
        return model


def frame_columns(
    times: np.ndarray, centres: list[np.ndarray], radii: list[float], captions: list[str]
) -> dict:
    """A :class:`ColumnDataSource`'s data of frames: ``times`` as shown, each ball's centres
    and (constant) radius as drawn, bottom ball first, and each frame's caption."""
    data = {"t": np.asarray(times, dtype=np.float32), "caption": captions}
    for ball, (centre, radius) in enumerate(zip(centres, radii, strict=True)):
        data[f"y{ball}"] = np.asarray(centre, dtype=np.float32)
        data[f"r{ball}"] = np.full(len(times), radius, dtype=np.float32)
    return data


def frame_at(data: dict, at: int, colors: list[str]) -> dict:
    """The drawn balls' data at frame ``at`` of ``data`` (:func:`frame_columns`), as
    :data:`FRAME_JS` draws them: the server's first frame of a drop."""
    at = min(max(at, 0), len(data["t"]) - 1)
    return {
        "x": [0.0] * len(colors),
        "y": [float(data[f"y{b}"][at]) for b in range(len(colors))],
        "r": [float(data[f"r{b}"][at]) for b in range(len(colors))],
        "color": list(colors),
    }


def new_frames() -> ColumnDataSource:
    """An empty source of frames."""
    return ColumnDataSource({"t": [], "caption": []})
