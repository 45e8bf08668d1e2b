"""The precomputed sweep cubes shipped in ``precomputed/`` (each made by ``twoball sweep``)."""

from __future__ import annotations

import os
from pathlib import Path

from twoball.errors import ParameterError

PRECOMPUTED = Path(__file__).resolve().parent.parent / "precomputed"


def cube_names() -> list[str]:
    """Names of the shipped cubes (``precomputed/NAME.zarr``)."""
    return sorted(path.name.removesuffix(".zarr") for path in PRECOMPUTED.glob("*.zarr"))


def cube_path(name: str) -> Path:
    """The store of a shipped cube; ValueError naming the cubes that exist."""
    path = PRECOMPUTED / f"{name}.zarr"
    if not (path / "zarr.json").is_file():
        raise ParameterError(f"no cube named {name!r}; shipped cubes: {', '.join(cube_names())}")
    return path


def load_cube(name: str | os.PathLike):
    """Open a sweep cube lazily as an ``xarray.Dataset`` (dims eps, mu, tau_ratio).

    ``name`` is a shipped cube ("paper", "map", "contacts"), or the path of any ``twoball sweep``
    store (a ``Path``, or a string ending in .zarr or holding a directory separator). Nothing is
    read until a slice is asked for; one eps slice reads one chunk per variable.
    """
    import xarray as xr

    text = os.fspath(name)
    is_path = isinstance(name, os.PathLike) or text.endswith(".zarr") or os.sep in text
    path = Path(text) if is_path else cube_path(text)
    return xr.open_zarr(path, consolidated=False)
