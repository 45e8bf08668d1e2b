"""Two-ball sweeps with the Hertz force (``twoball sweep ... --force hertz``): the cells of a
:class:`twoball.batch.sweep.Grid` computed by the compiled Hertz path, and the checks of its domain.

The store is the linear sweep's (same axes eps, mu, tau_ratio, same variables, chunks and
done-markers: :mod:`twoball.batch.sweep` writes it); only the cells and a few attributes differ.

**How H enters.** The Hertz force is not scale-free: a Hertz contact lasts about
3.2 m^(2/5) v^(-1/5), so the contact time against the flight time, and with it every bounce
ratio, moves with the impact speed sqrt(2H). The drop height is therefore a fixed option of
the sweep (``--height``, as for the linear force) and stored in the cube's ``height``
attribute, in the Hertz unit of length L = (m1 g / k_h)^(2/3), the static compression of the
lower ball under its own weight (``height_units``; docs/model.md, "The Hertz force"). A study
over H is several cubes, one per height (the shipped ``hertz-h1e2`` and ``hertz-h1e4``). The
gap axis tau_ratio is in units of the calibrated Hertz floor contact time, which itself depends
on H (:func:`twoball.stacks.hertz_contact.floor_contact_time`).

**Each cell** is exactly ``simulate_stack([mu], eps, tau_ratio, height=H, force="hertz")`` (or
``eps=[eps, eps12]``): the same calibration (:func:`twoball.stacks.hertz_contact.damping_factor` per
eps, :func:`twoball.stacks.hertz_contact.calibration_speeds`), the same release heights, the same
compiled run (:func:`twoball.kernels.hertz.run`), called for a whole chunk at once from
:func:`run_cells`, which releases the GIL so that a sweep's threads compute in parallel.

**Domain.** Before any work the grid's corners are checked with
:func:`twoball.stacks.check_stack` (``force="hertz"``): eps >= 0.05, mu <= 1e4, the
Hunt-Crossley damping at the impact speed (a smallest H for each eps) and the rounding of the
heights. Each limit is monotone along every axis (the damping, lam = Lambda(eps) / sqrt(2H) at
the floor and Lambda(eps12) / ((1 + eps) sqrt(2H)) between the balls, falls with eps and does
not depend on mu or the gap; the rounding is monotone in mu and grows with the gap), so the corners
decide. A cell that still fails keeps NaN in h1 or h2 and says
why in ``status`` (:data:`STATUS_FLAGS`).
"""

from __future__ import annotations

import math
from itertools import product

import numpy as np

from twoball.errors import ParameterError, Status
from twoball.jit import njit
from twoball.kernels import hertz as hertz_kernel

FORCE = "hertz"
SOLVER = "hertz_kernel"
HEIGHT_UNITS = (
    "L = (m1 g / k_h)^(2/3), the lower ball's static Hertz compression (dimensionless "
    "height X = z / L)"
)
TIME_UNITS = "sqrt(L / g) (dimensionless time tau)"
# how a Hertz cell ends: the kernel's codes (twoball.errors.Status)
STATUS_FLAGS = {
    int(Status.DONE): "second_apex_reached",
    int(Status.REST): "upper_ball_came_to_rest",
    int(Status.PHASE_LIMIT): "step_limit_reached",
    int(Status.FAILED): "integrator_failed",
}
# Cells per second one local thread computes, for the plan's estimate, cautious as the linear
# one: 1.0-1.5 ms a cell over the paper's ranges at H = 1e2 and 1e4, 2.6-2.8 ms while other jobs
# shared the cores (the shipped cubes; docs/performance.md).
DROPS_PER_WORKER_SECOND = 400
# Cells in a default chunk: a few seconds of compute (one chunk of the linear sweep's size would
# take half a minute), so that a stopped sweep loses little.
CHUNK_DROPS = 2_500
VARIABLE_UNITS = {"h1": HEIGHT_UNITS, "h2": HEIGHT_UNITS, "h_icm": HEIGHT_UNITS,
                  "x2_0": HEIGHT_UNITS, "t1": TIME_UNITS, "t2": TIME_UNITS}  # fmt: skip


def check_corners(eps: tuple, mu: tuple, tau_ratio: tuple, height: float, eps12) -> None:
    """Refuse a Hertz grid whose corners (each axis's first and last value) lie outside the
    Hertz domain: ParameterError naming the corner, the parameter and its allowed range."""
    from twoball.stacks import check_stack

    for e, m, t in product(eps, mu, tau_ratio):
        try:
            check_stack([m], e if eps12 is None else [e, eps12], t, height=height, force=FORCE)
        except ParameterError as error:
            raise ParameterError(
                f"the hertz sweep's corner eps = {e:g}, mu = {m:g}, tau_ratio = {t:g} "
                f"(height {height:g}) is outside the Hertz domain: {error}"
            ) from None


def cell_inputs(eps: float, eps12: float | None, mu: float, tau_ratio: float, height: float):
    """(masses, lam, x_start) of one cell, as :func:`twoball.stacks.hertz.solve_compiled` makes
    them."""
    from twoball.stacks import hertz_contact, release_heights

    restitutions = np.array([eps, eps if eps12 is None else eps12], dtype=float)
    masses = np.cumprod([1.0, mu])
    lam = np.array([hertz_contact.damping_factor(float(e)) for e in restitutions])
    lam /= hertz_contact.calibration_speeds(masses, restitutions, height)
    tau_f = hertz_contact.floor_contact_time(float(restitutions[0]), height)
    return masses, lam, release_heights(height, (tau_ratio,), tau_f)


@njit(nogil=True)
def run_cells(masses, lam, x_start, apex_h, apex_t, contacts, status):
    """Every cell (row) to the upper ball's second apex: its two apexes (NaN: none), its
    ball-ball contacts before the first apex, how it ended. Runs without the GIL."""
    none = np.empty(0)
    for c in range(masses.shape[0]):
        code, _end, apexes, _contacts, first, _samples, _steps, _nodes = hertz_kernel.run(
            masses[c], lam[c], x_start[c], 2, np.inf, none
        )
        found = 0
        for row in range(apexes.shape[0]):
            if apexes[row, 0] == 1.0 and found < 2:
                apex_t[found, c] = apexes[row, 1]
                apex_h[found, c] = apexes[row, 2]
                found += 1
        # (as the linear sweep: no first apex, no count of the contacts before it)
        contacts[c] = first[1] if found else np.nan
        status[c] = code


def compute_block(
    eps: np.ndarray,
    mu: np.ndarray,
    tau_ratio: np.ndarray,
    *,
    height: float,
    eps12: float | None = None,
) -> dict[str, np.ndarray]:
    """Every cube variable on the outer grid of the three 1-d arrays, with the Hertz force:
    the same variables and types as :func:`twoball.batch.sweep.compute_block`."""
    from twoball.model import icm_height
    from twoball.observables import ratios

    eps, mu, tau_ratio = (np.asarray(a, dtype=float) for a in (eps, mu, tau_ratio))
    shape = (eps.size, mu.size, tau_ratio.size)
    cells = math.prod(shape)
    masses, lam, x_start = np.empty((cells, 2)), np.empty((cells, 2)), np.empty((cells, 2))
    for c, (e, m, t) in enumerate(product(eps, mu, tau_ratio)):
        masses[c], lam[c], x_start[c] = cell_inputs(float(e), eps12, float(m), float(t), height)
    apex_h = np.full((2, cells), np.nan)
    apex_t = np.full((2, cells), np.nan)
    contacts = np.full(cells, np.nan)
    status = np.zeros(cells, dtype=np.int8)
    run_cells(masses, lam, x_start, apex_h, apex_t, contacts, status)
    x2_0 = x_start[:, 1].reshape(shape)
    eps01 = eps[:, None, None]
    h_icm = icm_height(
        height, x2_0 - height, eps01, eps01 if eps12 is None else eps12, mu[None, :, None]
    )
    h1, h2 = (a.reshape(shape) for a in apex_h)
    return {
        "h1": h1,
        "h2": h2,
        "t1": apex_t[0].reshape(shape),
        "t2": apex_t[1].reshape(shape),
        "contacts_first": contacts.reshape(shape),
        "h_icm": h_icm,
        "x2_0": x2_0,
        **ratios(h1, h2, x2_0, h_icm),
        "delayed_rebound": h2 > h1,  # False where h2 is NaN
        "status": status.reshape(shape),
    }


def annotate(dataset, height: float) -> None:
    """The Hertz cube's own attributes, on the linear template (units, solver, status flags)."""
    for name, units in VARIABLE_UNITS.items():
        dataset[name].attrs["units"] = units
    dataset["status"].attrs["flag_values"] = list(STATUS_FLAGS)
    dataset["status"].attrs["flag_meanings"] = " ".join(STATUS_FLAGS.values())
    dataset["tau_ratio"].attrs["long_name"] = (
        "tau_d / tau_f, tau_f the Hertz floor contact time at this height"
    )
    dataset.attrs.update(
        {
            "title": "two-ball bounce sweep (twoball, Hertz force with Hunt-Crossley damping)",
            "force": FORCE,
            "height_units": HEIGHT_UNITS,
            "height_note": (
                "Hertz is not scale-free: every ratio depends on H, one cube per height "
                "(twoball/batch/hertz_sweep.py)"
            ),
            "solver": SOLVER + " (compiled Taylor series in dt = sqrt(delta) dtau on the contact "
            "forces' displacement, switches found on the series; docs/stacks.md)",
        }
    )
