"""Server hooks of the directory app: warm the compiled solver and open the map cube once per
server, at start-up, so that no session waits for numba (about 15 s without its disk cache)."""

from __future__ import annotations

import logging

import twoball

from .delayed_map import map_cube

log = logging.getLogger(__name__)


def on_server_loaded(server_context) -> None:
    """Run every compiled path once (dense sampling included) and open the map cube."""
    twoball.simulate(0.9, 0.01, 0.01, until="second", dense_output=True)
    try:
        map_cube()
    except (OSError, ValueError) as error:  # the map scene shows this too
        log.warning("the map cube could not be opened: %s", error)
