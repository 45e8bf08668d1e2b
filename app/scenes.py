"""The scenes of the explorer: the one registry, in tab order (names, titles, captions, viewers).

Plain data: the state (app/state.py) reads the names for the URL, the explorer (app/explorer.py)
builds a scene's viewer when it is first shown, importing its module then.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass


@dataclass(frozen=True)
class SceneEntry:
    """A scene of the explorer: its tab's title, the caption above it, its viewer class."""

    title: str
    caption: str  # what the scene shows and what to look for
    viewer: str  # "module:Class" in this package, imported when the scene is first built

    def viewer_class(self) -> type:
        """The scene's viewer class (a :class:`scene.Scene`)."""
        module, _, name = self.viewer.partition(":")
        return getattr(importlib.import_module(f".{module}", __package__), name)


# The one registry of scenes, in tab order; their names are the URL's ``scene``.
SCENE_REGISTRY = {
    "drop": SceneEntry(
        "Drop",
        "The heights of both balls from release to the small ball's second highest point. "
        "Look for the orange peaks: a second one higher than the first is a delayed rebound.",
        "drop:DropScene",
    ),
    "closeup": SceneEntry(
        "First collision",
        "The first collision, slowed down: the floor's push on the big ball and the push "
        "between the balls. Each separate hump of the ball force is one contact. The floor "
        "force starts with a jump, not from 0: in this spring-and-dashpot model the damping "
        "pushes in proportion to the speed, largest at the moment of touching. Each ball's "
        "height is its own, from contact: X1 is 0 where the big ball just touches the floor, "
        "X2 where the small ball just touches the big one resting on the floor; below 0 they "
        "are pressed in: X2 as deep as the big ball sinks into the floor, plus the squash "
        "between the balls.",
        "closeup:CloseUpScene",
    ),
    "map": SceneEntry(
        "Delayed-rebound map",
        "Every mass ratio and gap at once: outlined in black where the second bounce is the "
        "higher one. Click a point to choose those balls for the other tabs.",
        "delayed_map:MapScene",
    ),
    "accuracy": SceneEntry(
        "Accuracy",
        "General-purpose ODE solvers on the same drop at several tolerances, against the "
        "exact solver: how far off they are, and how long they take.",
        "accuracy:AccuracyScene",
    ),
    "stack": SceneEntry(
        "Stack",
        "Beyond the paper: a stack of 2 to 8 balls dropped together, each lighter than the one "
        "below. Compare the top ball's bounce with the textbook chain of collisions.",
        "stack:StackScene",
    ),
}

SCENES = tuple(SCENE_REGISTRY)
