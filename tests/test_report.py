"""``twoball report``: the paper's table from the cubes, checked against independent runs."""

from __future__ import annotations

import re

import numpy as np
import pytest

import twoball
from twoball.batch.sweep import Axis, Grid, sweep
from twoball.cli import main
from twoball.observables import BALLS
from twoball.studies.report import close_up_row, contact_row, sweep_rows

PAPER_VALUES = ["12.3 %", "93 %", "22 %", "all", "0.87 to 1.27", "0.49 to 1.48", "1 to 12"]


@pytest.fixture(scope="module")
def small_cube(tmp_path_factory):
    """A small cube over the paper's ranges, with tau values above 0.85 and one at 0.7."""
    grid = Grid(
        Axis("eps", 0.6, 1.0, 3),
        Axis("mu", 0.01, 1 / 3, 3),
        Axis("tau_ratio", 0.05, 0.95, 4),  # 0.05, 0.35, 0.65, 0.95
        height=1e4,
    )
    store = tmp_path_factory.mktemp("cube") / "small.zarr"
    sweep(grid, store, workers=1, progress=False)
    return grid, twoball.load_cube(store)


def test_sweep_rows_count_what_simulate_finds(small_cube):
    grid, cube = small_cube
    results = [
        twoball.simulate(e, m, t)
        for e in grid.eps.values()
        for m in grid.mu.values()
        for t in grid.tau_ratio.values()
    ]
    delayed = [r for r in results if r.delayed_rebound]
    below = [r for r in results if r.h1_over_icm < 1.0]
    both = [r for r in delayed if r.h1_over_icm < 1.0]
    high = [r for r in results if r.drop.tau_ratio > 0.85]
    near = [r for r in results if r.drop.tau_ratio == 0.65]
    rows = sweep_rows(cube)
    assert rows[0].ours.endswith(f"({len(delayed)} of {len(results)})")
    assert rows[1].ours.endswith(f"({len(both)} of {len(delayed)})")
    assert rows[2].ours.endswith(f"({len(both)} of {len(below)})")
    within = sum(abs(r.h1_over_icm - 1.0) <= 0.05 for r in high)
    assert rows[3].ours.startswith(f"{100 * within / len(high):.1f} % ({within} of {len(high)})")
    worst = max(abs(r.h1_over_icm - 1.0) for r in high)
    assert rows[3].ours.endswith(f"largest deviation {100 * worst:.1f} %")
    low, top = min(r.h1_over_icm for r in near), max(r.h1_over_icm for r in near)
    assert rows[4].ours == f"{low:.2f} to {top:.2f}" and "0.6500" in rows[4].note
    assert [row.paper for row in rows] == PAPER_VALUES[:6]


def test_contact_row_counts_what_simulate_finds(tmp_path):
    grid = Grid(Axis("eps", 0.816, 0.816, 1), Axis("mu", 1e-4, 1.0, 5, "log"),
                Axis("tau_ratio", 1e-4, 1e-2, 3, "log"))  # fmt: skip
    sweep(grid, tmp_path / "c.zarr", workers=1, progress=False)
    counts = {
        (m, t): twoball.simulate(0.816, m, t, until="first").contacts_first[BALLS]
        for m in grid.mu.values()
        for t in grid.tau_ratio.values()
    }
    row = contact_row(twoball.load_cube(tmp_path / "c.zarr"))
    paper_range = [c for (m, _), c in counts.items() if m >= 0.01]
    assert row.ours.startswith(f"{min(paper_range)} to {max(paper_range)} for mu in 0.01..1/3")
    assert f"up to {max(counts.values())} for mu >= 0.0001" in row.ours
    assert max(counts.values()) > max(paper_range)  # more contacts at smaller mu


def test_close_up_row_against_sampled_forces():
    row = close_up_row()
    assert row.ours == "4 contacts, 4 of them during floor contact"
    # independently: on a dense sample, the ball force never acts without the floor force
    end = twoball.simulate(0.9, 0.01, 0.01, until="first").end_time
    result = twoball.simulate(0.9, 0.01, 0.01, until="first", t_eval=np.linspace(0, end, 300001))
    force = result.trajectory
    pushing = force.f12 > 0
    assert pushing.any() and (force.f01[pushing] > 0).all()
    starts = np.flatnonzero(pushing[1:] & ~pushing[:-1])
    assert starts.size == 4


def test_report_command_prints_the_table(capsys):
    assert main(["report"]) == 0
    out = capsys.readouterr().out
    lines = [line for line in out.splitlines() if line.startswith("| ")]
    assert len(lines) == 2 + 8 + 4 * 2  # and the Hertz rows of the two shipped Hertz cubes
    for value in PAPER_VALUES:
        assert f"| {value} |" in out
    share = re.search(r"\| 12\.3 % \| ([\d.]+) % \((\d+) of (\d+)\)", out)
    cube = twoball.load_cube("paper")
    assert int(share.group(3)) == cube.h1.size == 50**3
    # the count agrees with h2 > h1 on the stored values, up to float32 ties
    stored = int((cube.h2 > cube.h1).sum())
    assert abs(stored - int(share.group(2))) <= 5


def test_report_bad_cube_name_exits_2(capsys):
    assert main(["report", "--paper-cube", "nonesuch"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "nonesuch" in err and "paper" in err
