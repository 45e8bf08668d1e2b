"""What a class takes away for a worksheet: the scene on screen as CSV, computed when asked.

A drop's file starts with its parameters and results as ``# name = value`` lines, then its
state at the plotted times (the drop scene's samples: even in time, 9 through every contact,
the apexes exact) at full precision, in the units on screen. A map's file is the slice on
screen, one row per (mu, tau_d/tau_f).
"""

from __future__ import annotations

import io

import numpy as np
import xarray as xr

import twoball
from twoball.observables import BALLS
from twoball.units import Units


def _header(lines: dict[str, object]) -> str:
    """``# name = value`` lines; a parameter's number to 12 significant digits, as a link
    carries it (state.url_query): eps = 0.57, not the 0.5700000000000001 of a slider's
    arithmetic (a teacher's trial). The results, written by :func:`_number`, keep every digit."""
    return "".join(f"# {name} = {_parameter(value)}\n" for name, value in lines.items())


def _parameter(value: object) -> object:
    return f"{value:.12g}" if isinstance(value, float) else value


def _number(value: float | None) -> str:
    return "none" if value is None else repr(float(value))


def drop_csv(result: twoball.Result, samples: twoball.Trajectory, units: Units) -> str:
    """The drop's parameters and results, then its state at ``samples``' times, in ``units``."""
    drop, si = result.drop, units.length != 1.0
    speed = units.length / units.time
    header = {
        "eps": drop.eps,
        "eps12": drop.eps12,
        "mu": drop.mu,
        "tau_ratio": drop.tau_ratio,
        "H": drop.height,
        "units": "metres, seconds, newtons" if si else "dimensionless",
        "h1": _number(None if result.h1 is None else result.h1 * units.length),
        "h2": _number(None if result.h2 is None else result.h2 * units.length),
        "h2_over_h1": _number(result.h2_over_h1),
        "h_icm": _number(result.h_icm * units.length),
        "released_at": _number(result.x2_0 * units.length),
        "ball_contacts_in_first_bounce": result.contacts_first[BALLS],
        "delayed_rebound": result.delayed_rebound,
    }
    names = ("t", "x1", "x2", "v1", "v2", "f01", "f12")
    scales = (units.time, units.length, units.length, speed, speed, units.force, units.force)
    columns = [getattr(samples, name) * scale for name, scale in zip(names, scales, strict=True)]
    out = io.StringIO()
    out.write(_header(header))
    labels = (" [s]", " [m]", " [m]", " [m/s]", " [m/s]", " [N]", " [N]") if si else [""] * 7
    out.write(",".join(name + label for name, label in zip(names, labels, strict=True)) + "\n")
    np.savetxt(out, np.column_stack(columns), delimiter=",", fmt="%.17g")
    return out.getvalue()


def slice_csv(shown: xr.Dataset, variable: str, about: dict[str, object]) -> str:
    """The map's slice on screen: ``about`` as header lines, then mu, tau_ratio, ``variable``
    and whether the drop is a delayed rebound, one row per grid point."""
    table = shown[[variable, "delayed_rebound"]].transpose("mu", "tau_ratio")
    mu, tau = np.meshgrid(table["mu"].values, table["tau_ratio"].values, indexing="ij")
    rows = np.column_stack(
        [
            mu.ravel(),
            tau.ravel(),
            table[variable].values.ravel(),
            table["delayed_rebound"].values.ravel().astype(int),
        ]
    )
    out = io.StringIO()
    out.write(_header(about))
    out.write(f"mu,tau_ratio,{variable},delayed_rebound\n")
    np.savetxt(out, rows, delimiter=",", fmt=["%.17g", "%.17g", "%.17g", "%d"])
    return out.getvalue()
