"""What every scene shares: it recomputes only while it is on screen, and only when stale."""

from __future__ import annotations

import holoviews as hv
import panel as pn
import param

from .state import ExplorerState

hv.renderer("bokeh")  # the plotting backend of every scene, also without ``panel serve``

MODEL_PARAMETERS = ("eps", "eps12", "mu", "tau_ratio", "height")


class Scene(pn.viewable.Viewer):
    """A scene of the explorer. Subclasses implement :meth:`update` and :meth:`__panel__`.

    A change of the watched parameters marks the scene stale and, if it is ``active`` (on
    screen), bumps ``revision``, which redraws its views; each view calls :meth:`current`
    first. A scene off screen is recomputed when it comes on screen.
    """

    state = param.ClassSelector(class_=ExplorerState, doc="The session's shared state.")
    active = param.Boolean(default=False, doc="Whether the scene is on screen.")
    revision = param.Integer(default=0, doc="Counts the recomputations (plots depend on it).")

    watched: tuple[str, ...] = (*MODEL_PARAMETERS, "units")

    def __init__(self, **params):
        super().__init__(**params)
        self._stale = True
        self.computations = 0
        self.state.param.watch(self._state_changed, list(self.watched))
        self.param.watch(self._activated, "active")

    def _state_changed(self, *events: param.parameterized.Event) -> None:
        self._stale = True
        if self.active:
            self.revision += 1

    def _activated(self, event: param.parameterized.Event) -> None:
        if event.new and self._stale:
            self.revision += 1

    def current(self) -> None:
        """Recompute what the scene shows if the state changed since; every view calls this
        first, so the work is done once per change, and only for a scene that is drawn."""
        if self._stale:
            self._stale = False
            self.computations += 1
            self.update()

    def update(self) -> None:
        raise NotImplementedError
