"""The explorer: controls beside one tab per scene; only the scene on screen is computed."""

from __future__ import annotations

from collections.abc import Mapping
from urllib.parse import urlencode

import panel as pn
import param

from twoball import jit

from .accuracy import AccuracyScene
from .closeup import CloseUpScene
from .controls import Controls
from .delayed_map import MapScene
from .drop import DropScene
from .scene import MODEL_PARAMETERS
from .state import SCENES, ExplorerState, read_query, url_query

TITLES = {
    "drop": "Drop",
    "closeup": "First collision",
    "map": "Delayed-rebound map",
    "accuracy": "Accuracy",
}
URL_DELAY_MS = 300
SCENE_CLASSES = {
    "drop": DropScene,
    "closeup": CloseUpScene,
    "map": MapScene,
    "accuracy": AccuracyScene,
}


class Explorer(pn.viewable.Viewer):
    """One session of the app, built from a URL query (``{key: text}``)."""

    state = param.ClassSelector(class_=ExplorerState)

    def __init__(self, query: Mapping[str, str] | None = None, **params):
        params.setdefault("state", ExplorerState())
        super().__init__(**params)
        values, messages = read_query(query or {}, self.state)
        self.state.param.update(**values)
        self.controls = Controls(state=self.state, messages=messages)
        self.scenes = {name: SCENE_CLASSES[name](state=self.state) for name in SCENES}
        self.tabs = pn.Tabs(
            *((TITLES[name], scene) for name, scene in self.scenes.items()),
            dynamic=True,
            active=SCENES.index(self.state.scene),
            sizing_mode="stretch_width",
        )
        self.tabs.param.watch(self._tab_chosen, "active")
        self.state.param.watch(self._scene_chosen, "scene")
        self.scenes[self.state.scene].active = True

    def _tab_chosen(self, event: param.parameterized.Event) -> None:
        self.state.scene = SCENES[event.new]

    def _scene_chosen(self, event: param.parameterized.Event) -> None:
        for name, scene in self.scenes.items():
            scene.active = name == event.new
        self.tabs.active = SCENES.index(event.new)

    def follow_location(self, location: pn.io.location.Location) -> None:
        """Keep the browser's URL equal to the state (bad values in it are replaced at once).

        The URL is rewritten shortly after a change, once for a burst of changes: sent in the
        same update as the plots it delayed them by about 65 ms (benchmarks/app_latency.py).
        """
        pending = False

        def write() -> None:
            nonlocal pending
            pending = False
            location.search = "?" + urlencode(url_query(self.state))

        def changed(*events: param.parameterized.Event) -> None:
            nonlocal pending
            document = pn.state.curdoc
            if document is None or document.session_context is None:
                write()
            elif not pending:
                pending = True
                document.add_timeout_callback(write, URL_DELAY_MS)

        self.state.param.watch(changed, [*MODEL_PARAMETERS, "scene"])
        pn.state.onload(write)  # once the browser has reported its own URL

    @staticmethod
    def _compiling_notice() -> list[pn.pane.Alert]:
        """A note on a page opened while the server's first start compiles the solver."""
        if jit.state == "compiled":
            return []
        text = (
            "First start on this machine: the solver is still being compiled (up to a minute). "
            "Until then drops are computed in plain Python: the same results, a little slower."
        )
        return [pn.pane.Alert(text, alert_type="info", sizing_mode="stretch_width")]

    def sidebar(self) -> pn.Column:
        """The controls (and a note while the solver compiles), for the page's sidebar."""
        return pn.Column(*self._compiling_notice(), self.controls, sizing_mode="stretch_width")

    def __panel__(self) -> pn.viewable.Viewable:
        """The explorer without the page's template (main.py puts it in one)."""
        return pn.Row(
            pn.Column(pn.pane.Markdown("## Two-ball bounce explorer"), self.sidebar(), width=340),
            self.tabs,
            sizing_mode="stretch_width",
        )
