"""The precomputed sweep cubes, shipped as package data in ``twoball/precomputed/`` (each made
by ``twoball sweep``), so that a plain wheel carries them."""

from __future__ import annotations

import json
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

    Nothing is read until a slice is asked for; one eps slice reads one chunk per variable.

    Parameters
    ----------
    name : str or path
        A shipped cube ("paper", "map", "contacts"), or the path of any ``twoball sweep`` store
        (a ``Path``, or a string ending in .zarr or holding a directory separator).

    Returns
    -------
    xarray.Dataset
        h1, h2, the contact counts and the ratios (docs/model.md, "What is measured") on the
        cube's axes, with each variable's ``long_name`` and the sweep's arguments as attributes.

    Raises
    ------
    ParameterError
        If the store does not exist or is not a Zarr store.

    Examples
    --------
    >>> import twoball
    >>> cube = twoball.load_cube("map")
    >>> dict(cube.sizes)
    {'eps': 21, 'mu': 73, 'tau_ratio': 81}
    >>> float(cube.h2_over_h1.sel(eps=0.816, method="nearest").max()) > 1  # a delayed rebound
    True
    """
    import xarray as xr

    text = os.fspath(name)
    is_path = isinstance(name, os.PathLike) or text.endswith(".zarr") or os.sep in text
    path = Path(text) if is_path else cube_path(text)
    if not (path / "zarr.json").is_file():
        what = "does not exist" if not path.exists() else "is not a Zarr store (no zarr.json)"
        raise ParameterError(f"cannot open the cube {path}: it {what}")
    try:
        node = json.loads((path / "zarr.json").read_text()).get("node_type")
    except (OSError, ValueError, AttributeError):
        node = None
    if node != "group":
        what = "an array inside a store" if node == "array" else "not a Zarr group"
        raise ParameterError(
            f"cannot open the cube {path}: it is {what}; give the store's directory "
            "(what twoball sweep wrote, e.g. cube.zarr)"
        )
    return xr.open_zarr(path, consolidated=False)
