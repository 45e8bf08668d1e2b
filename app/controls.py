"""The controls: sliders for eps, mu and tau_d/tau_f, presets, units, and the advanced inputs.

mu and tau_d/tau_f move on logarithmic sliders (the slider holds log10 of the value and shows
the value itself). A typed value follows one rule (:func:`state.typed_value`): a number out of
range is clamped to the nearest allowed value, text that is no number keeps the value in use,
and either way a message under the inputs says so; the app keeps running.
"""

from __future__ import annotations

import functools
import math
import re
from collections.abc import Callable

import panel as pn
import param
from bokeh.models import CustomJS, CustomJSTickFormatter

from twoball import presets

from .scene import PENDING_JS, Built, Folded, alert, for_a_room, join, later
from .state import ExplorerState, app_range, metres_text, preset_drop, typed_value

# the slider holds log10 of the value and shows the value (a model per slider: one per session)
POWER_OF_TEN = "return Number((10 ** tick).toPrecision(3)).toString()"
# A slider's step, one press of an arrow key: about a hundredth of its range, a change the plot
# shows (0.001 of eps and 0.01 of a decade, a thousandth and a five-hundredth, moved nothing in
# sight: a teacher's trial); a log slider's is a step in log10, 0.05: a factor of 1.12. A value
# typed or linked keeps its digits (?eps=0.9137): the step snaps only the handle drawn, from
# which a key press moves on a step (0.92)
EPS_STEP = 0.01
LOG_STEP = 0.05
LOG_SLIDERS = ("mu", "tau_ratio")
# A log slider's value, moved by a user, to 3 significant digits, as its title shows it: ten to
# its log10 gave mu = 0.0446683592151 in a shared link (a teacher's trial); 0.0447 is 0.0016 %
# of a step off, and a factor 1.12 a step keeps every step's value distinct
LOG_DIGITS = 3
MARKDOWN_SPECIALS = re.compile(r"([\\`*_{}\[\]()#+!|<>~])")
LONG_WORD = re.compile(r"\S{41,}")  # a bad value quoted in a message is cut to 40 characters


def plain(text: str) -> str:
    """``text`` shown literally in a Markdown pane: a value typed or read from the URL can
    neither link elsewhere nor load an image; a long one is cut."""
    text = LONG_WORD.sub(lambda match: match.group()[:40] + "...", text)
    text = text.replace("://", ":\u200b//")  # no bare address for a linkifier to catch
    return MARKDOWN_SPECIALS.sub(r"\\\1", text)


# what a preset's drop shows, under its sources, where it is not what a class expects; the
# numbers are the solver's (tests/app/test_app_scenes.py recomputes them). The tennis preset
# holds the balls touching, as the rule books' balls are held in a demonstration: a teacher
# expecting the classic 3.7 times saw a first bounce below the 1 m drop and "delayed rebound"
PRESET_NOTES = {
    "tennis": "Why no textbook bounce: held touching (tau_d/tau_f = 0.01), the tennis ball is "
    "hit while the basketball is still squashed, and rises to 0.92 times the drop height, "
    "its second bounce 2.5 times higher (a delayed rebound); a gap of tau_d/tau_f = 1 gives "
    "the textbook 3.7 times.",
}


MEANINGS = """
**eps**: how bouncy each contact is (1: no energy lost, 0: no bounce).

**mu = m2/m1**: how much lighter the upper ball is (0.01: a hundred times).

**tau_d/tau_f**: how far apart the balls start: the time the gap takes to close, over one
floor contact's duration (0.01: nearly touching).

{height}

**ICM** (dotted green line): the textbook prediction, one contact after the other (floor,
then ball): up to 9 times the drop height for elastic balls and a very light upper ball.
"""
# the drop height's meaning in the units shown (in metres it spoke of a dimensionless height)
HEIGHT_MEANINGS = {
    "dimensionless": "**H**: the drop height in units of the lower ball's squash under its own "
    "weight, m1 g / k.",
    "SI": "**drop height [m]**: in metres (the model's H counts it in units of the lower "
    f"ball's squash under its own weight, m1 g / k = {presets.length_scale() * 1e3:.2g} mm "
    "for this basketball).",
}


# On a phone (narrower than 768 px, as PAGE_CSS in app/explorer.py) a slider's handle is a
# thumb's touch target, 44 x 44 CSS px (WCAG 2.5.5, as the player's buttons: app/animation.py):
# the theme's 15 px handle was hard to catch (a teacher's trial). A transparent border of the
# target surrounds the disc drawn, 24 px; the slider's margins make room for the disc, not the
# border, which reaches over the blank between sliders (with room for the border, three sliders
# took 90 px more, and the Map's plot and its sliders no longer fitted a phone's screen). Set on
# the slider, not :host, whose sizes the theme's style sheet, linked after this one, sets;
# Bokeh's sizes from the handle's (its place, the margins) are set again with it. The track
# is 12 px shorter at each end, where the handle stands half past it (at eps = 1 it stood past
# the sidebar's edge). A wider screen keeps 15 px.
PHONE_SLIDER = """
@media (max-width: 767px) {
  .noUi-target {
    --handle-width: 44px; --handle-height: 44px; --handle-right: -22px;
    --handle-top: calc(-1 * (44px - var(--slider-size)) / 2 - 1px);
    --slider-margin: calc((24px - var(--slider-size)) / 2 + 1.5px);
  }
  .noUi-target.noUi-horizontal { width: calc(100% - 24px); margin-left: 12px; margin-right: 12px; }
  .noUi-handle {
    box-sizing: border-box; border: 10px solid transparent !important;
    background-clip: padding-box;
  }
}
"""
# the drawn disc's margin in the handle's box on a phone (PHONE_SLIDER's border)
PHONE_HANDLE_BORDER = 10


class Released:
    """A slider whose release is handled at once, and marks the page as waiting for it.

    Panel waits 50 ms (``Syncable._debounce``) after every change from the browser, to take a
    drag's stream of ``value`` changes as one. The explorer reads only ``value_throttled``, sent
    once on release, so the wait only delayed every redraw by 50 ms (tools/bokehclient.py
    measures it: a move's patch 57 ms after the release with the wait, 7 ms without). The
    release also marks the page as waiting (:data:`scene.PENDING_JS`), in the browser: Panel's
    ``jscallback`` cannot bind ``value_throttled`` (it syncs no such property), so the callback
    goes on the Bokeh model, which has it.
    """

    _debounce = 0
    # Panel counts every change from a browser as the server process's "busy" time (a param
    # change with watchers, twice a move: ~1 ms); that count serves its busy spinner, which
    # the page does without (explorer.py), so a release is not counted
    _busy__ignore = ["value", "value_throttled"]

    def __init__(self, **params):
        # no value bubble: the title shows the value, and after a click the bubble stayed up
        # over the title ('eps (re[0.208]n)', a new user)
        params.setdefault("tooltips", False)
        params["stylesheets"] = [*params.get("stylesheets", []), PHONE_SLIDER]
        super().__init__(**params)

    def _get_model(self, doc, root=None, parent=None, comm=None):
        model = super()._get_model(doc, root, parent, comm)
        model.js_on_change("value_throttled", CustomJS(code=PENDING_JS))  # (app/static)
        return model

    # The browser sends ``value`` at every step of a drag (and once more before each release);
    # Panel handled each as a change (its event queue, param's watchers: about 1 ms of server
    # CPU, tests/app/test_app_controls.py counts them), for nothing: the explorer reads the
    # release.
    # So Panel does not follow ``value`` from the browser, and takes the released value as
    # ``value`` too (Panel's own ``config.throttled`` does the same, for every slider of a page,
    # but still handles each ``value``). The value the server sets still goes to the browser.
    @property
    def _linked_properties(self) -> tuple[str, ...]:
        return tuple(name for name in super()._linked_properties if name != "value")

    def _process_property_change(self, props: dict) -> dict:
        if "value_throttled" in props:
            props = {**props, "value": props["value_throttled"]}
        return super()._process_property_change(props)


class ReleasedSlider(Released, pn.widgets.FloatSlider):
    """:class:`Released` for real numbers, taken as the slider shows them: the browser's
    start + n * step carries the float's noise (eps 0.01 + 56 * 0.01 = 0.5700000000000001,
    which a worksheet's header printed: a teacher's trial), cut to 12 significant digits."""

    def _process_property_change(self, props: dict) -> dict:
        props = super()._process_property_change(props)
        for name in ("value", "value_throttled"):
            if isinstance(props.get(name), float):
                props[name] = float(f"{props[name]:.12g}")
        return props


class ReleasedIntSlider(Released, pn.widgets.IntSlider):
    """:class:`Released` for whole numbers."""


def two_ball_sliders(state: ExplorerState, short: bool = False) -> dict[str, pn.widgets.Widget]:
    """eps, mu and tau_ratio: eps a slider made from the state's parameter (its bounds, linked
    both ways, the state set on release only); mu and tau_ratio sliders of log10 of the value,
    which Panel's from_param cannot make (it has no transform), for the caller to link
    (:func:`follow_log_sliders`). ``short``: titles short enough for a projector's 20 px."""
    return {
        "eps": ReleasedSlider.from_param(
            state.param.eps,
            name="eps" if short else "eps (restitution)",
            step=EPS_STEP,
            format="0.000",  # (a linked eps's third digit: 0.914)
            throttled=True,
        ),
        "mu": _log_slider("mu = m2/m1" if short else "mu = m2/m1 (log scale)", "mu"),
        "tau_ratio": _log_slider(
            "tau_d/tau_f" if short else "tau_d/tau_f (log scale)", "tau_ratio"
        ),
    }


def _log_slider(label: str, name: str) -> pn.widgets.FloatSlider:
    low, high = app_range(name)
    return ReleasedSlider(
        label=label,
        start=math.log10(low),
        end=math.log10(high),
        step=LOG_STEP,
        format=CustomJSTickFormatter(code=POWER_OF_TEN),
    )


def log_slider_value(position: float) -> float:
    """The value a log slider at ``position`` (log10) sets: :data:`LOG_DIGITS` significant
    digits of ten to it (-1.35: 0.0447)."""
    return float(f"{10.0**position:.{LOG_DIGITS}g}")


def follow_log_sliders(sliders: dict[str, pn.widgets.Widget], state: ExplorerState) -> None:
    """Move the log sliders to the state (eps follows it by its link)."""
    for name in LOG_SLIDERS:
        slider = sliders[name]
        value = getattr(state, name)
        shown = min(max(math.log10(value), slider.start), slider.end)
        # already there (a round trip through log10 is not exact), or the value this slider
        # set, where the user left it (moved to log10(0.0447), the handle would leave its step)
        if abs(shown - slider.value) < 1e-9 or log_slider_value(slider.value) == value:
            continue
        with param.edit_constant(slider):
            slider.param.update(value=shown, value_throttled=shown)


def height_within_range(height: float, convert: Callable[[float], float], digits: int) -> str:
    """The drop height H as text in the units ``convert`` gives, to ``digits`` significant
    digits or as many more as it takes for the text, typed back, to be within the app's range:
    the highest drop in metres, 9,948.975 m, showed as 9.95e+03, and that, typed back, was
    refused as above the range (a helper's trial)."""
    low, high = (convert(end) for end in app_range("height"))
    value = convert(height)
    for more in range(digits, 18):
        text = f"{value:.{more}g}"
        if low <= float(text) <= high:
            return text
    return repr(value)


def on_a_phone() -> bool:
    """Whether this session's browser says it is a phone's ("Mobi" in its User-Agent, as
    Mozilla advises; a tablet's says it not, and has the width for the sidebar)."""
    headers = pn.state.headers or {}
    agent = next((v for k, v in headers.items() if k.lower() == "user-agent"), "")
    return "Mobi" in agent


# Shown under 768 px only (PAGE_CSS in app/explorer.py): a phone turned sideways has the
# sidebar beside the scene, with its own sliders
PHONE_ONLY = "@media (min-width: 768px) { :host { display: none !important; } }"


def phone_only(*widgets: pn.viewable.Viewable, css_class: str) -> pn.Column:
    """``widgets`` in a column shown on a phone only (:data:`PHONE_ONLY`)."""
    return pn.Column(
        *widgets,
        sizing_mode="stretch_width",
        stylesheets=[PHONE_ONLY],
        css_classes=[css_class],
    )


def announce_moves(slider: pn.widgets.Widget, state: ExplorerState) -> None:
    """A release of ``slider`` fires the state's ``slider_moved``: the messages of a bad URL
    value go (:class:`Controls`), as at a release of the sidebar's two-ball sliders. (A
    slider made by ``from_param`` is also released when the state moves it: as the sidebar's
    eps, which always cleared them then.)"""
    slider.param.watch(lambda event: setattr(state, "slider_moved", True), "value_throttled")


class PhoneSliders(Built):
    """The three two-ball sliders again, for a phone's scene (the Drop, the Close-up, the
    Accuracy), right under its plot: the sidebar's, below the scene, the player, the lesson
    and the preset, lay 1100 px under it, and a student could not watch the plot while
    dragging (a teacher's trial). Made only for a phone's page (:func:`on_a_phone`: no other
    page pays for them), shown under 768 px; both sets follow the state, and a release of
    either clears the URL's messages (the state's ``slider_moved``)."""

    state = param.ClassSelector(class_=ExplorerState)

    def __init__(self, **params):
        super().__init__(**params)
        self.sliders = two_ball_sliders(self.state)
        self._syncing = False
        announce_moves(self.sliders["eps"], self.state)  # (eps is linked by Panel)
        for name in LOG_SLIDERS:
            self.sliders[name].param.watch(
                lambda event, name=name: self._moved(name, event.new), "value_throttled"
            )
        self.state.param.watch(self._follow, list(LOG_SLIDERS))
        self._follow()

    def _moved(self, name: str, value: float | None) -> None:
        if not self._syncing and value is not None:
            self.state.slider_moved = True
            setattr(self.state, name, log_slider_value(value))

    def _follow(self, *events: param.parameterized.Event) -> None:
        self._syncing = True
        try:
            follow_log_sliders(self.sliders, self.state)
        finally:
            self._syncing = False

    def layout(self) -> pn.viewable.Viewable:
        return phone_only(*self.sliders.values(), css_class="twoball-phone-sliders")


def message_box() -> pn.pane.Alert:
    """A hidden box for messages about bad input."""
    return alert(
        "",
        alert_type="warning",
        visible=False,
        sizing_mode="stretch_width",
        styles={"overflow-wrap": "anywhere"},
    )


class Controls(Built):
    """Widgets bound to one :class:`ExplorerState`, and the message box for bad input."""

    state = param.ClassSelector(class_=ExplorerState)

    def __init__(self, messages: list[str] | None = None, **params):
        super().__init__(**params)
        self._applying_preset = False
        self._syncing = False  # True while the widgets follow the state
        # the two-ball controls (preset, units, sliders, their meanings) are made when a scene
        # they drive is first shown (show_scene_controls): a page opened on the Stack, which
        # has sliders of its own, never showed them yet paid 14-16 ms of its opening for them
        # (benchmarks/app_open.py)
        self.two_ball: pn.Column | None = None
        # (a watcher, not @param.depends: _show_state reads which parameters changed)
        self.state.param.watch(
            self._show_state, ["eps", "mu", "tau_ratio", "height", "eps12", "units"]
        )
        # a slider released, here or elsewhere (a phone's copies under the plot: PhoneSliders)
        self.state.param.watch(lambda event: self.show_messages([]), "slider_moved")
        # on a phone the sidebar lies under the scenes, 1500 px down, where a student never saw
        # that a link's value was refused: the URL's messages go above the scenes, into the
        # layout the explorer gives (``messages_at``), which shows them when it is built
        self.messages_above_scenes = on_a_phone()
        self.messages_at: pn.layout.ListLike | None = None
        self.show_messages(messages or [])
        self.scene_controls = pn.Column(sizing_mode="stretch_width")
        self.explained: Folded | None = None  # (a projector's: layout)

    def _make_two_ball(self) -> None:
        """The preset, the units and the two-ball sliders (``two_ball``) and the sliders'
        meanings, following the state, placed in the layout if it is built."""
        # on a projector the titles are short: at 20 px a long one pushed its value out of
        # the sidebar ("mu = m2/m1 (log scale): 0.09...")
        self.sliders = two_ball_sliders(self.state, short=self.state.presentation)
        for name, slider in self.sliders.items():
            slider.param.watch(
                lambda event, name=name: self._slider_moved(name, event.new), "value_throttled"
            )
        self.preset = pn.widgets.Select(
            label="Preset",
            options={"(custom)": ""} | {p.label: key for key, p in presets.PRESETS.items()},
            stylesheets=for_a_room(self.state.presentation),
        )
        self.preset.param.watch(self._apply_preset, "value")
        self.units = pn.widgets.RadioButtonGroup(
            label="Units",
            options={"dimensionless": "dimensionless", "metres, seconds": "SI"},
            value=self.state.units,  # (a link syncs changes only: a lesson's URL opens in SI)
        )
        self.units.link(self.state, value="units", bidirectional=True)
        self.meanings = pn.pane.Markdown(self._meanings(), sizing_mode="stretch_width")
        self.two_ball = pn.Column(
            self.preset, self.units, *self.sliders.values(), sizing_mode="stretch_width"
        )
        self._show_state()
        self._syncing = True  # a link's preset (state.read_query): shown, its drop already set
        try:
            self.preset.value = self.state.preset
        finally:
            self._syncing = False
        if self._layout is not None:  # (a page opened on the Stack, now on a two-ball scene)
            objects = self._layout.objects
            shown = [o for o in (self.scene_controls, self.advanced.button) if o in objects]
            self._layout.insert(self._layout.objects.index(shown[0]), self.two_ball)
            self._place_meanings(self._layout)

    def _place_meanings(self, layout: pn.Column) -> None:
        """The sliders' meanings at the foot of the controls."""
        if self.state.presentation:
            # On a projector the sliders' meanings are folded: open, their 720 px ran under
            # "advanced", and the sidebar scrolled, the button itself cut at the screen's foot
            # (1280x720, a teacher's trial); the teacher says what the sliders mean
            self.explained = Folded("what the sliders mean", lambda: [self.meanings])
            self.explained.button.visible = self.meanings.visible  # (show_scene_controls)
            layout.append(self.explained.place(layout))
        else:
            layout.append(self.meanings)

    # The message boxes, the preset's source and the advanced inputs are made when first
    # needed: most pages never show them, and each cost about a millisecond of a page's
    # opening to make (a text box, and its own watchers of the state)
    @functools.cached_property
    def preset_source(self) -> pn.pane.Markdown:
        """Where a chosen preset's numbers come from, under the preset, and its note
        (:data:`PRESET_NOTES`): smaller than the controls' text, but at least 13 px (0.8 em
        alone was 9.6 px, too small to read on a phone: a teacher's trial); 16 px on a
        projector."""
        return pn.pane.Markdown("", styles={"font-size": "max(13px, 0.8em)"})

    @functools.cached_property
    def height(self) -> pn.widgets.TextInput:
        """The drop height, typed (under "advanced")."""
        box = pn.widgets.TextInput(label="", width=140)
        self._inputs_follow_state(box, None)
        box.param.watch(self._height_typed, "value")
        return box

    @functools.cached_property
    def eps12(self) -> pn.widgets.TextInput:
        """The ball-ball restitution, typed (under "advanced"; empty: equal to eps)."""
        box = pn.widgets.TextInput(label="eps12 (ball-ball; empty: equal to eps)", width=140)
        # (not on the Stack: show_scene_controls)
        box.visible = self.two_ball is not None and self.two_ball.visible
        self._inputs_follow_state(None, box)
        box.param.watch(self._eps12_typed, "value")
        return box

    @functools.cached_property
    def message(self) -> pn.pane.Alert:
        """The URL's messages, at the top of the controls."""
        return message_box()

    @functools.cached_property
    def typed_message(self) -> pn.pane.Alert:
        """A typed value's message, under its input (at the top, a phone showed it out of view
        of the field just typed in)."""
        return message_box()

    def show_messages(self, messages: list[str], typed: bool = False) -> None:
        """Show the messages, literally: a typed value's under the inputs (``typed``), others at
        the top; either box is hidden when it has none, and new messages clear the old."""
        for name in ("message", "typed_message"):
            shown = messages if (name == "typed_message") == typed else []
            if not shown and name not in self.__dict__:  # (never made: nothing to clear)
                continue
            box = getattr(self, name)
            box.object = "\n\n".join(plain(m) for m in shown)
            box.visible = bool(shown)
        if "message" in self.__dict__ and self.message.visible:
            join(self.messages_at if self.messages_above_scenes else self._layout, self.message)

    def url_message_shown(self) -> bool:
        """Whether the URL's message box has something to say."""
        return "message" in self.__dict__ and self.message.visible

    def _slider_moved(self, name: str, value: float) -> None:
        """A slider released by the user: the messages go, and a log slider sets its value
        (eps is linked by Panel). A slider moved to follow the state (:meth:`_follow_state`)
        changes nothing."""
        if self._syncing or value is None:
            return
        self.state.slider_moved = True  # (the messages go)
        if name in LOG_SLIDERS:
            setattr(self.state, name, log_slider_value(value))

    def _apply_preset(self, event: param.parameterized.Event) -> None:
        """A preset chosen (its drop set, in metres), or shown for a link that names it
        (``_syncing``: the drop is already the preset's); "(custom)" forgets it."""
        self.state.preset = event.new
        preset = presets.PRESETS.get(event.new)
        if preset is None:
            self.preset_source.object = ""
            return
        if not self._syncing:
            self.show_messages([])
            self._applying_preset = True
            try:
                self.state.param.update(**preset_drop(event.new), units="SI")  # real balls
            finally:
                self._applying_preset = False
        join(self.two_ball, self.preset_source, at=1)
        note = PRESET_NOTES.get(event.new)
        self.preset_source.object = (
            f"Drop from {presets.DEFAULT_DROP_METRES:g} m. Sources: {preset.source}"
            + (f"\n\n{note}" if note else "")
        )

    def _height_typed(self, event: param.parameterized.Event) -> None:
        if not self._syncing:
            later(lambda: self._take_height(event.new))

    def _take_height(self, text: str) -> None:
        """A typed drop height: H, or metres when the units are SI (checked and reported in the
        units it was typed in, quoting what was typed: :func:`state.typed_value`)."""
        low, high = app_range("height")
        if self.state.units == "SI":
            metres = presets.metres_from_height
            value, message = typed_value(
                text,
                metres(self.state.height),
                metres(low),
                metres(high),
                "drop height",
                " m",
                shown=metres_text,  # (limits rounded: "from about 0.99 mm to 9.9 km")
            )
            # (H from metres kept within H's own range: the round trip gave 9.999999999999998
            # for the lowest, which the state refused with a traceback)
            value = min(max(presets.height_from_metres(value), low), high)
            label = "drop height [m]"
        else:
            value, message = typed_value(text, self.state.height, low, high, "height")
            label = "H"
        self.show_messages([f"{label}: {message}"] if message else [], typed=True)
        self.state.height = value
        self._show_state()

    def _eps12_typed(self, event: param.parameterized.Event) -> None:
        if not self._syncing:
            later(lambda: self._take_eps12(event.new))

    def _take_eps12(self, text: str) -> None:
        """A typed eps12 (:func:`state.typed_value`); empty or "none": equal to eps."""
        if text.strip().lower() in ("", "none"):
            value, message = None, None
        else:
            value, message = typed_value(text, self.state.eps12, *app_range("eps12"), "eps12")
        self.show_messages([message] if message else [], typed=True)  # (it names eps12)
        self.state.eps12 = value
        self._show_state()

    def _show_state(self, *events: param.parameterized.Event) -> None:
        """Move the widgets to the state (after a preset, a map click or a URL); a change not
        made by the preset unselects it."""
        moved = any(e.name != "units" for e in events)
        made = self.two_ball is not None
        if made and moved and not self._applying_preset and self.preset.value:
            self.preset.value = ""
        self._syncing = True
        try:
            self._follow_state()
        finally:
            self._syncing = False

    def _follow_state(self) -> None:
        if self.two_ball is not None:
            follow_log_sliders(self.sliders, self.state)
            if self.meanings.object != self._meanings():
                self.meanings.object = self._meanings()
        self._inputs_follow_state(self.__dict__.get("height"), self.__dict__.get("eps12"))

    def _inputs_follow_state(
        self, height: pn.widgets.TextInput | None, eps12: pn.widgets.TextInput | None
    ) -> None:
        """The typed inputs (those made: :attr:`height`, :attr:`eps12`) to the state."""
        s = self.state
        if height is not None:
            si = s.units == "SI"
            height.label = "drop height [m]" if si else "H (dimensionless drop height)"
            # metres to three digits (the default H read 0.994898 m), H to six; a height typed
            # stays as typed while it is the drop's
            if not self._shows_height(height.value):
                convert, digits = (presets.metres_from_height, 3) if si else (float, 6)
                height.value = height_within_range(s.height, convert, digits)
        # set only when changed: param's update reads every parameter of the widget first
        # (0.3 ms at every slider move, for inputs that rarely change)
        text = "" if s.eps12 is None else f"{s.eps12:.6g}"
        if eps12 is not None and eps12.value != text:
            eps12.value = text

    def _meanings(self) -> str:
        return MEANINGS.format(height=HEIGHT_MEANINGS[self.state.units])

    def _shows_height(self, text: str) -> bool:
        """Whether the drop height box's ``text`` is the drop's height in the units shown."""
        try:
            typed = float(text)
        except ValueError:
            return False
        height = presets.height_from_metres(typed) if self.state.units == "SI" else typed
        return math.isclose(height, self.state.height, rel_tol=1e-12)

    def layout(self) -> pn.viewable.Viewable:
        # its inputs are made, and join the page, when it is first opened (app/scene.Folded);
        # the message above the boxes: below them, a laptop showed it under the window's edge
        # (y = 865 of 768), and a wrong H seemed silently undone
        self.advanced = Folded("advanced", lambda: [self.typed_message, self.height, self.eps12])
        # the URL's message box joins the page when it first has something to say
        # (show_messages): empty in every page's first document, it cost 0.6 kB
        # (a scene's own controls join it when such a scene is first shown: show_scene_controls)
        layout = pn.Column(
            *(
                [self.message]
                if self.url_message_shown() and not self.messages_above_scenes
                else []
            ),
            *([self.two_ball] if self.two_ball is not None else []),
            *([self.scene_controls] if self.scene_controls.objects else []),
            sizing_mode="stretch_width",
        )
        layout.append(self.advanced.place(layout))
        if self.two_ball is not None:
            self._place_meanings(layout)
        return layout

    def show_scene_controls(self, own: pn.viewable.Viewable | None) -> None:
        """Show a scene's own controls (:meth:`Scene.own_controls`) instead of the two-ball
        sliders, their preset and meanings, which do not drive it (the Stack scene showed two
        'eps' sliders, one of them doing nothing there); None shows the two-ball ones."""
        if own is None and self.two_ball is None:
            self._make_two_ball()
        if own is not None and own not in self.scene_controls.objects:
            self.scene_controls.append(own)
            if self._layout is not None:  # (an empty box in every page cost a Bokeh column)
                at = self._layout.objects.index(self.advanced.button)
                join(self._layout, self.scene_controls, at)
        for shown in self.scene_controls.objects:
            shown.visible = shown is own
        if self.two_ball is not None:
            self.two_ball.visible = self.meanings.visible = own is None
        if self.explained is not None:  # (a projector's fold of the meanings: layout)
            self.explained.button.visible = own is None
        # eps12 is the two-ball drop's (a stack has its own eps per contact): typed on the Stack
        # scene it changed the link and nothing on screen (a teacher's trial)
        if "eps12" in self.__dict__:
            self.eps12.visible = own is None
