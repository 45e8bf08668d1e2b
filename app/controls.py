"""The controls: sliders for eps, mu and tau_d/tau_f, presets, units, and the advanced inputs.

mu and tau_d/tau_f move on logarithmic sliders (the slider holds log10 of the value and shows
the value itself). Every typed value is checked by :func:`state.validate`: a bad one shows a
message and falls back, the app keeps running.
"""

from __future__ import annotations

import html
import math

import panel as pn
import param
from bokeh.models import CustomJSTickFormatter

from twoball import presets

from .state import APP_RANGES, ExplorerState, validate

# the slider holds log10 of the value and shows the value (a model per slider: one per session)
POWER_OF_TEN = "return Number((10 ** tick).toPrecision(3)).toString()"
LOG_SLIDERS = ("mu", "tau_ratio")


class Controls(pn.viewable.Viewer):
    """Widgets bound to one :class:`ExplorerState`, and the message box for bad input."""

    state = param.ClassSelector(class_=ExplorerState)

    def __init__(self, messages: list[str] | None = None, **params):
        super().__init__(**params)
        # plain text, escaped: a message quotes what was typed or put in the URL, which must
        # never render as a link or an image (Alert would read it as Markdown)
        self.message = pn.pane.HTML(
            "",
            visible=False,
            sizing_mode="stretch_width",
            styles={
                "background": "#fff3cd",
                "color": "#664d03",
                "border": "1px solid #ffe69c",
                "border-radius": "6px",
                "padding": "0 12px",
                "overflow-wrap": "anywhere",
            },
        )
        self.sliders = {
            "eps": pn.widgets.FloatSlider(
                label="eps (restitution)",
                start=APP_RANGES["eps"][0],
                end=1.0,
                step=0.001,
                format="0.000",
            ),
            "mu": self._log_slider("mu = m2/m1 (log scale)", "mu"),
            "tau_ratio": self._log_slider("tau_d/tau_f (log scale)", "tau_ratio"),
        }
        for name, slider in self.sliders.items():
            slider.param.watch(
                lambda event, name=name: self._slider_moved(name, event.new), "value_throttled"
            )
        self.preset = pn.widgets.Select(
            label="Preset",
            options={"(custom)": ""} | {p.label: key for key, p in presets.PRESETS.items()},
        )
        self.preset.param.watch(self._apply_preset, "value")
        self.preset_source = pn.pane.Markdown("", styles={"font-size": "0.8em"})
        self.units = pn.widgets.RadioButtonGroup(
            label="Units", options={"dimensionless": "dimensionless", "metres, seconds": "SI"}
        )
        self.units.link(self.state, value="units", bidirectional=True)
        self.height = pn.widgets.TextInput(label="", width=140)
        self.eps12 = pn.widgets.TextInput(label="eps12 (ball-ball; empty: equal to eps)", width=140)
        self.height.param.watch(self._height_typed, "value")
        self.eps12.param.watch(self._eps12_typed, "value")
        self._syncing = False  # True while the widgets follow the state
        self.state.param.watch(
            self._show_state, ["eps", "mu", "tau_ratio", "height", "eps12", "units"]
        )
        self._show_state()
        self.show_messages(messages or [])

    @staticmethod
    def _log_slider(label: str, name: str) -> pn.widgets.FloatSlider:
        low, high = APP_RANGES[name]
        return pn.widgets.FloatSlider(
            label=label,
            start=math.log10(low),
            end=math.log10(high),
            step=0.01,
            format=CustomJSTickFormatter(code=POWER_OF_TEN),
        )

    def show_messages(self, messages: list[str]) -> None:
        """Show the messages (or hide the box when there are none)."""
        self.message.object = "".join(f"<p>{html.escape(text)}</p>" for text in messages)
        self.message.visible = bool(messages)

    def _slider_moved(self, name: str, value: float) -> None:
        if self._syncing or value is None:
            return
        number = 10.0**value if name in LOG_SLIDERS else value
        self.show_messages([])
        self.state.param.update(**{name: number})

    def _apply_preset(self, event: param.parameterized.Event) -> None:
        preset = presets.PRESETS.get(event.new)
        if preset is None:
            self.preset_source.object = ""
            return
        self.show_messages([])
        self.state.param.update(
            eps=preset.eps,
            eps12=preset.eps12,
            mu=preset.mu,
            tau_ratio=preset.tau_ratio,
            height=presets.height_from_metres(presets.DEFAULT_DROP_METRES),
        )
        self.preset_source.object = (
            f"Drop from {presets.DEFAULT_DROP_METRES:g} m. Sources: {preset.source}"
        )

    def _height_typed(self, event: param.parameterized.Event) -> None:
        if self._syncing:
            return
        si = self.state.units == "SI"
        try:
            typed = float(event.new)
        except ValueError:
            typed = event.new
        if si and isinstance(typed, float) and math.isfinite(typed):
            typed = presets.height_from_metres(typed)
        value, message = validate("height", typed, self.state.height)
        if message and si:  # say it in the units the teacher typed
            low, high = (presets.metres_from_height(h) for h in APP_RANGES["height"])
            message = (
                f"drop height must be a number of metres in [{low:.3g}, {high:.3g}]; got "
                f"{event.new!r}. Using {presets.metres_from_height(value):.3g} m."
            )
        elif message:
            message = f"H: {message}"
        self._apply_typed("height", value, message)

    def _eps12_typed(self, event: param.parameterized.Event) -> None:
        if self._syncing:
            return
        value, message = validate("eps12", event.new, self.state.eps12)
        self._apply_typed("eps12", value, message and f"eps12: {message}")

    def _apply_typed(self, name: str, value: float | None, message: str | None) -> None:
        """Show the message (or clear an earlier one) and set the state on the document's next
        tick: a text input's callback does not hold the document lock, and the scenes redraw
        Bokeh models when the state changes (that raised "_pending_writes should be non-None")."""

        def apply() -> None:
            self.show_messages([message] if message else [])
            self.state.param.update(**{name: value})
            self._show_state()

        document = pn.state.curdoc
        if document is not None and document.session_context is not None:
            document.add_next_tick_callback(apply)
        else:
            apply()

    def _show_state(self, *events: param.parameterized.Event) -> None:
        """Move the widgets to the state (after a preset, a map click or a URL)."""
        self._syncing = True
        try:
            self._follow_state()
        finally:
            self._syncing = False

    def _follow_state(self) -> None:
        s = self.state
        for name, slider in self.sliders.items():
            value = getattr(s, name)
            shown = math.log10(value) if name in LOG_SLIDERS else value
            shown = min(max(shown, slider.start), slider.end)
            if abs(shown - slider.value) < 1e-9:
                continue  # already there (a round trip through log10 is not exact)
            with param.edit_constant(slider):
                slider.param.update(value=shown, value_throttled=shown)
        si = s.units == "SI"
        self.height.label = "drop height [m]" if si else "H (dimensionless drop height)"
        height = presets.metres_from_height(s.height) if si else s.height
        self.height.param.update(value=f"{height:.6g}")
        self.eps12.param.update(value="" if s.eps12 is None else f"{s.eps12:.6g}")

    def __panel__(self) -> pn.viewable.Viewable:
        advanced = pn.Card(
            self.height, self.eps12, title="advanced", collapsed=True, sizing_mode="stretch_width"
        )
        return pn.Column(
            self.message,
            self.preset,
            self.preset_source,
            self.units,
            *self.sliders.values(),
            advanced,
            sizing_mode="stretch_width",
        )
