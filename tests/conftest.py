"""Compile the exact solver once, before any test starts a subprocess that needs it.

The app and sweep tests start servers and workers that load numba's disk cache; writing that
cache here first means no two processes compile the same kernels at the same time.
"""

import twoball


def pytest_sessionstart(session):
    twoball.simulate(0.9, 0.01, 0.01, dense_output=True)
