"""The animations of the drop and Stack scenes, played in the browser.

A scene's frames are sent once per drop, when its player first moves
(:meth:`Animation.send_frames`): a ColumnDataSource with each frame's time as shown ``t``,
whether it is in slow motion ``slow`` and each ball's centre as drawn ``y<b>`` (ball ``b`` from
the bottom); the balls' radii and colours stay in the drawn balls' source. The player's frame
number picks a frame in the browser (app/static/animation.js), and the balls, the time cursor on the
heights and the caption change there alone (Bokeh's ``setv(..., {sync: false})``: nothing is
sent back). Drawn on the server, a frame cost 3 ms of server CPU, 71 ms a second for each
student playing, so a class pressing play at once saturated two cores (docs/performance.md,
"A class at once"); now the server only hears the frame number, which Panel's player syncs.
Captions are written in the browser, from ``t``: sent as text they were a third of a stack's
frames on the network.
"""

from __future__ import annotations

from collections.abc import Callable
from decimal import ROUND_HALF_UP, Decimal

import numpy as np
import panel as pn
from bokeh.models import ColumnDataSource, CustomJS, Span, Title

# What draws a frame in the page, app/static/animation.js (loaded with the page, app/main.py):
# also what keeps a playing player's frame number there (about 3 kB that every page's document
# carried when it was the callback's own code)
DRAW_FRAME_JS = (
    "twoballDrawFrame({frames, balls, cursor, title, unit, trail, trail_lines, player});"
)


def time_caption(time: float, unit: str, slow: bool = False) -> str:
    """A frame's caption as app/static/animation.js writes it: four significant digits, a tie
    rounded up (JavaScript's toPrecision; Python's formats round it to even), no trailing zeros
    (the two languages' shortest forms differ only below 1e-4 and above 1e16, never an
    animation's times)."""
    exact = Decimal(time)
    if exact != 0:
        exact = exact.quantize(Decimal(1).scaleb(exact.adjusted() - 3), rounding=ROUND_HALF_UP)
    shown = float(exact)
    text = str(int(shown)) if shown.is_integer() else repr(shown)
    return f"t = {text} {unit}" + (" (slow)" if slow else "")  # (the stage is 220 px wide)


def no_frames() -> dict:
    """A frames source's data with no frame (and the columns of one ball)."""
    return {"t": [], "slow": [], "y0": []}


class Animation:
    """The frames of a scene's animation and what draws them in the browser.

    ``balls`` is the stage's source of drawn balls (x, y, r, color), ``cursor`` the time
    cursor on the heights, ``title`` the stage's title, ``trail`` (optional) a source of each
    ball's top up to the frame (columns t, top0, top1, ...)."""

    def __init__(
        self,
        balls: ColumnDataSource,
        cursor: Span,
        title: Title,
        trail: ColumnDataSource | None = None,
    ):
        self.frames = ColumnDataSource(no_frames())
        self.balls, self.cursor, self.title = balls, cursor, title
        self.on_frame = CustomJS(
            args=dict(
                frames=self.frames,
                balls=balls,
                cursor=cursor,
                title=title,
                unit="tau",
                trail=trail,
                trail_lines=[],
                player=None,
            ),
            code=DRAW_FRAME_JS,
        )
        self.frames.js_on_change("data", self.on_frame)
        # (a redraw asked for without new frames: :meth:`redraw`)
        self.frames.js_on_change("tags", self.on_frame)
        self._unsent: tuple | None = None  # (the drop's frames, sent when asked: send_frames)
        self._trail_lines: list = []
        self._redraws = 0

    def draw_trails_with(self, lines: list) -> None:
        """Draw the trail (into its renderers ``lines``) as the animation plays, and at once
        when they are shown."""
        self.on_frame.args = {**self.on_frame.args, "trail_lines": lines}
        self._trail_lines = lines
        for line in lines:
            line.js_on_change("visible", self.on_frame)

    def show(
        self,
        times: np.ndarray,
        centres: list[float],
        frames: Callable[[], list[np.ndarray]],
        radii: list[float],
        colors: list[str],
        at: int,
        unit: str,
        slow: np.ndarray | None = None,
    ) -> None:
        """A new drop: its frames' ``times`` as shown; each ball's centre as drawn at frame
        ``at`` (where the player is: drawn from here), bottom ball first, with its radius and
        colour; ``frames()`` each ball's centres at every frame, which frames are ``slow``
        motion. The frames are computed and sent when the player first moves
        (:meth:`send_frames`): a class that only moves sliders does not pay for them (a
        stack's are 35 kB)."""
        at = min(max(at, 0), len(times) - 1)
        slow = np.zeros(len(times), dtype=bool) if slow is None else slow
        self.balls.data = {  # (the browser reads the radii when the frames come)
            "x": [0.0] * len(centres),
            "y": [float(centre) for centre in centres],
            "r": [float(radius) for radius in radii],
            "color": list(colors[: len(centres)]),
        }
        shown = np.asarray(times, dtype=np.float32)  # (the caption's digits are the browser's)
        self.cursor.location = float(shown[at])
        self.title.text = time_caption(float(shown[at]), unit, bool(slow[at]))
        self._unsent = (shown, frames, slow, unit)
        if any(line.visible for line in self._trail_lines):  # the trail is drawn from them
            self.send_frames()
        elif len(self.frames.data["t"]):  # the last drop's, which would be drawn if played now
            self.frames.data = no_frames()

    def send_frames(self) -> None:
        """Send the drop's frames to the browser, if they are not there yet."""
        if self._unsent is None:
            return
        shown, frames, slow, unit = self._unsent
        self._unsent = None
        if self.on_frame.args["unit"] != unit:
            self.on_frame.args = {**self.on_frame.args, "unit": unit}
        data = {"t": shown, "slow": slow.astype(np.uint8)}
        for ball, centre in enumerate(frames()):
            data[f"y{ball}"] = np.asarray(centre, dtype=np.float32)
        self.frames.data = data

    def redraw(self) -> None:
        """Draw the frame the player is at again, in the page, from the frames it has (a
        change of the frames' tags, a few bytes): trails asked for while paused after a play,
        with the frames already in the page, were drawn only when it moved again."""
        self._redraws += 1
        self.frames.tags = [self._redraws]

    def clear(self) -> None:
        """No frames and no balls (a refused drop)."""
        self._unsent = None
        self.balls.data = {"x": [], "y": [], "r": [], "color": []}
        self.frames.data = no_frames()


# the scenes' players: 25 frames a second, once through, at most 520 px wide
PLAYER_DEFAULTS = dict(
    label="Animation",
    start=0,
    value=0,
    interval=40,
    loop_policy="once",
    show_loop_controls=False,
    sizing_mode="stretch_width",
    max_width=520,
)


# On a phone (narrower than 768 px, as PAGE_CSS in app/explorer.py) the player's buttons are
# touch targets of at least 44 x 44 CSS px (WCAG 2.5.5; Panel draws them 31 x 21): nine of
# them wrap onto a second row, the player as tall as they need (in a column too, which gave
# it a basis of its 80 px: the Stack's second row lay over the text under it). A wider
# screen keeps them.
PHONE_PLAYER = """
@media (max-width: 767px) {
  :host { height: auto !important; flex-basis: auto !important; }
  :host div:has(> button.play) { flex-wrap: wrap; }
  :host button { min-width: 44px; min-height: 44px; }
}
"""


class FramePlayer(pn.widgets.Player):
    """Panel's player, each of whose frames is drawn in the browser by an
    :class:`Animation`, given its model when the model is made; its first move after a new
    drop has the drop's frames sent. Where it stands on the server is ``value_throttled``
    (a playing page does not send each frame: app/static/animation.js)."""

    def __init__(self, animation: Animation, **params):
        params = {**PLAYER_DEFAULTS, **params}
        params["stylesheets"] = [*params.get("stylesheets", []), PHONE_PLAYER]
        super().__init__(**params)
        self._on_frame = animation.on_frame
        self.param.watch(lambda _: animation.send_frames(), "value")

    def _get_model(self, doc, root=None, parent=None, comm=None):
        model = super()._get_model(doc, root, parent, comm)
        self._on_frame.args = {**self._on_frame.args, "player": model}
        model.js_on_change("value", self._on_frame)
        return model
