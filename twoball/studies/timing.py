"""The one way the studies time a run: the median wall time of repeated calls."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable


def median_seconds(run: Callable[[], object], repeats: int) -> float:
    """Median wall time in seconds of ``repeats`` calls of ``run`` (at least one).

    >>> median_seconds(lambda: None, 3) >= 0.0
    True
    """
    times = []
    for _ in range(max(repeats, 1)):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return statistics.median(times)
