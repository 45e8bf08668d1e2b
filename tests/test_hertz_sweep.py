"""Two-ball Hertz sweeps (twoball/batch/hertz_sweep.py): cells equal to simulate_stack, resume after
an interruption, the corners refused outside the Hertz domain, the shipped cubes, and the Hertz
statistics of ``twoball report`` against counts of their own."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
import xarray as xr

import twoball
import twoball.batch.sweep
from twoball.batch.hertz_sweep import STATUS_FLAGS, compute_block
from twoball.batch.sweep import VARIABLES, Axis, Grid, plan, sweep
from twoball.cli import main
from twoball.errors import ParameterError, Status
from twoball.model import icm_height
from twoball.stacks import simulate_stack
from twoball.studies.hertz_report import HERTZ_CUBES, hertz_rows


def _small(height=1e2, eps12=None, chunks=None) -> Grid:
    return Grid(
        Axis("eps", 0.6, 1.0, 2),
        Axis("mu", 0.02, 0.3, 2),
        Axis("tau_ratio", 0.05, 0.9, 3),
        height=height,
        eps12=eps12,
        chunks=chunks,
        force="hertz",
    )


def _value(x) -> float:
    return math.nan if x is None else x


@pytest.mark.parametrize("height, eps12", [(1e2, None), (1e4, 0.8)])
def test_every_cell_equals_simulate_stack_with_the_hertz_force(tmp_path, height, eps12):
    grid = _small(height, eps12)
    cube = sweep(grid, tmp_path / "h.zarr", workers=1, progress=False).load()
    assert cube.attrs["force"] == "hertz" and cube.attrs["height"] == height
    assert "k_h" in cube.attrs["height_units"] and "k_h" in cube.h1.attrs["units"]
    for i, e in enumerate(grid.eps.values()):
        for j, m in enumerate(grid.mu.values()):
            for k, t in enumerate(grid.tau_ratio.values()):
                eps = e if eps12 is None else [e, eps12]
                run = simulate_stack([m], eps, t, height=height, force="hertz", throw=False)
                cell = cube.isel(eps=i, mu=j, tau_ratio=k)
                top = run.apexes[-1]
                expected = {
                    "h1": _value(run.h1),
                    "h2": _value(run.h2),
                    "t1": top[0][0] if top else math.nan,
                    "t2": top[1][0] if len(top) > 1 else math.nan,
                    "contacts_first": run.contacts_first[1],
                    "x2_0": run.stack.x_start[-1],
                    "status": int(run.status),
                }
                for name, value in expected.items():
                    stored = float(cell[name])
                    assert stored == value or (math.isnan(stored) and math.isnan(value)), name
                assert bool(cell.delayed_rebound) == (run.h2 is not None and run.h2 > run.h1)
                # the paper's h_ICM (docs/model.md), with the gap the Hertz drop starts from
                gap = run.stack.x_start[-1] - height
                icm = icm_height(height, gap, e, e if eps12 is None else eps12, m)
                assert float(cell.h_icm) == pytest.approx(icm, rel=1e-12)


def test_resume_after_an_interruption_gives_the_same_cube(tmp_path, monkeypatch):
    grid = _small(chunks=(1, 1, 3))  # four chunks
    whole = sweep(grid, tmp_path / "whole.zarr", workers=1, progress=False).load()
    store = tmp_path / "cut.zarr"
    real = twoball.batch.sweep._write_chunk
    written = []

    def dies_after_two(*args):
        if len(written) == 2:
            raise KeyboardInterrupt  # as a Ctrl-C between two chunks
        real(*args)
        written.append(args[3])

    monkeypatch.setattr(twoball.batch.sweep, "_write_chunk", dies_after_two)
    with pytest.raises(KeyboardInterrupt):
        sweep(grid, store, workers=1, progress=False)
    monkeypatch.setattr(twoball.batch.sweep, "_write_chunk", real)
    markers = sorted(p.name for p in (store / "_progress").iterdir() if p.name != "zarr.json")
    assert len(markers) == 2 and not (store.with_name("cut.zarr.lock")).exists()
    finished = {key: (store / "h1" / f"c.{key}").stat().st_mtime_ns for key in markers}
    resumed = sweep(grid, store, workers=1, progress=False).load()
    for key, mtime in finished.items():  # not computed again
        assert (store / "h1" / f"c.{key}").stat().st_mtime_ns == mtime
    for name in VARIABLES:
        np.testing.assert_array_equal(resumed[name].values, whole[name].values, name)
    assert resumed.attrs == whole.attrs | {"sweep_command": resumed.attrs["sweep_command"]}


@pytest.mark.parametrize(
    "words, named",
    [
        (["--eps", "0.01:1:3"], "eps must be at least 0.05"),
        (["--mu", "0.01:1e5:3:log"], "1e+05"),
        (["--height", "1e-4"], "height must be at least"),
    ],
)
def test_the_corners_outside_the_hertz_domain_are_refused_in_one_line(
    tmp_path, capsys, words, named
):
    base = {"--eps": "0.5:1:3", "--mu": "0.01:1/3:3", "--tau-ratio": "0.01:1:3"}
    given = dict(zip(words[::2], words[1::2], strict=True))
    argv = ["sweep", str(tmp_path / "h.zarr"), "--quiet", "--force", "hertz"]
    for flag, value in {**base, **given}.items():
        argv += [flag, value]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("twoball: error:") and named in err
    assert "corner" in err and "Hertz domain" in err and "Traceback" not in err
    assert not (tmp_path / "h.zarr").exists()


def test_the_library_refuses_a_hertz_grid_naming_the_parameter_and_its_range():
    with pytest.raises(ParameterError, match=r"eps must be at least 0\.05.*\[0\.05, 1\]"):
        Grid(Axis("eps", 0.02, 1, 3), Axis("mu", 0.1, 0.1, 1), Axis("tau_ratio", 0.1, 0.1, 1),
             force="hertz")  # fmt: skip
    with pytest.raises(ValueError, match="force must be linear or hertz"):
        Grid(Axis("eps", 0.9, 0.9, 1), Axis("mu", 0.1, 0.1, 1), Axis("tau_ratio", 0.1, 0.1, 1),
             force="spring")  # fmt: skip
    # the linear force accepts the same eps: the check is the Hertz one
    Grid(Axis("eps", 0.02, 1, 3), Axis("mu", 0.1, 0.1, 1), Axis("tau_ratio", 0.1, 0.1, 1))


def test_the_command_line_runs_a_hertz_sweep_and_says_what_it_undertakes(tmp_path, capsys):
    argv = ["sweep", str(tmp_path / "h.zarr"), "--eps", "0.9", "--mu", "0.05:0.1:2",
            "--tau-ratio", "0.3", "--height", "100", "--force", "hertz", "--quiet"]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "2 drops (1 x 2 x 1)" in out and "complete" in out
    cube = twoball.load_cube(tmp_path / "h.zarr")
    assert "--force hertz" in cube.attrs["sweep_command"]
    run = simulate_stack([0.05], 0.9, 0.3, height=100, force="hertz")
    assert float(cube.h2.isel(eps=0, mu=0, tau_ratio=0)) == run.h2
    # the estimate is the Hertz one: 400 cells/s a worker, not the linear 11 000
    grid = Grid(Axis("eps", 0.5, 1, 50), Axis("mu", 0.01, 1 / 3, 50),
                Axis("tau_ratio", 0.01, 1, 50), force="hertz")  # fmt: skip
    assert "about 2.6 min on 2 workers" in plan(grid, 2)
    # the Hertz size limit: 4e6 drops need --large
    huge = ["sweep", str(tmp_path / "x.zarr"), "--eps", "0.5:1:2001", "--mu", "0.01:0.3:2000",
            "--tau-ratio", "0.3", "--force", "hertz", "--quiet"]  # fmt: skip
    assert main(huge) == 2
    err = capsys.readouterr().err
    assert "4,000,000 drops needs --large" in err and not (tmp_path / "x.zarr").exists()


@pytest.mark.parametrize("where", ["last", "before another option"])
def test_sweep_force_needs_its_value_and_says_so_in_one_line(tmp_path, capsys, where):
    """``sweep --force`` names the contact force and needs it. Given bare it was meant to be
    the old --large (so said the help), but argparse passed its empty constant through the
    type check: "must be linear or hertz; got ''", a value the user never typed."""
    argv = ["sweep", str(tmp_path / "c.zarr"), "--eps", "0.9", "--mu", "0.1", "--tau-ratio", "0.3"]
    argv += ["--force", "--quiet"] if where == "before another option" else ["--quiet", "--force"]
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "Traceback" not in err
    assert "argument --force: expected one argument" in err
    assert not (tmp_path / "c.zarr").exists()


def test_stack_method_with_the_linear_force_is_refused(capsys):
    assert main(["stack", "--mass-ratios", "0.2", "--method", "DOP853"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "hertz force only" in err and "DOP853" in err
    with pytest.raises(ParameterError, match="hertz force only"):
        simulate_stack([0.2], 0.9, 0.2, method="DOP853")
    assert main(["stack", "--mass-ratios", "0.2", "--method", "compiled"]) == 0


@pytest.mark.parametrize("name", HERTZ_CUBES)
def test_shipped_hertz_cube(name):
    cube = twoball.load_cube(name)
    assert cube.attrs["force"] == "hertz"
    assert dict(cube.sizes) == {"eps": 50, "mu": 50, "tau_ratio": 50}
    assert cube.eps.values[0] == 0.5 and cube.eps.values[-1] == 1.0
    assert cube.mu.values[-1] == np.float64(1 / 3) and cube.tau_ratio.values[0] == 0.01
    status = cube.status.values
    assert set(np.unique(status)) <= set(STATUS_FLAGS)
    # no cell is left NaN without a status that says why
    for variable in ("h1", "h2", "t1", "t2"):
        assert (status[np.isnan(cube[variable].values)] != int(Status.DONE)).all(), variable
    assert not np.isnan(cube.contacts_first.values).any()
    # a piece computed again is the stored one (to the float32 it is stored in)
    piece = cube.isel(eps=[0, 37, 49], mu=slice(0, None, 24), tau_ratio=slice(0, None, 16))
    piece = piece.load()
    fresh = compute_block(
        piece.eps.values, piece.mu.values, piece.tau_ratio.values, height=cube.attrs["height"]
    )
    for variable in VARIABLES:
        stored, again = piece[variable].values, fresh[variable].astype(piece[variable].dtype)
        if stored.dtype.kind != "f":
            np.testing.assert_array_equal(stored, again, variable)
            continue
        np.testing.assert_array_equal(np.isnan(stored), np.isnan(again), variable)
        finite = ~np.isnan(stored)
        np.testing.assert_array_max_ulp(stored[finite], again[finite], maxulp=1)


def test_hertz_rows_count_what_simulate_stack_finds(tmp_path):
    grid = _small(1e2)
    cube = sweep(grid, tmp_path / "h.zarr", workers=1, progress=False)
    runs = [
        simulate_stack([m], e, t, height=1e2, force="hertz")
        for e in grid.eps.values()
        for m in grid.mu.values()
        for t in grid.tau_ratio.values()
    ]

    def icm(r):  # the paper's h_ICM (docs/model.md), from the gap of the Hertz release
        e, m = r.stack.eps[0], r.stack.mass_ratios[0]
        return icm_height(1e2, r.stack.x_start[-1] - 1e2, e, e, m)

    delayed = [r for r in runs if r.h2 is not None and r.h2 > r.h1]
    below = [r for r in runs if r.h1 / icm(r) < 1.0]
    both = [r for r in delayed if r.h1 / icm(r) < 1.0]
    rows = hertz_rows(cube)
    assert rows[0].ours.endswith(f"({len(delayed)} of {len(runs)})")
    assert rows[1].ours.endswith(f"({len(both)} of {len(delayed)})") or not delayed
    assert rows[2].ours.endswith(f"({len(both)} of {len(below)})") or not below
    assert "H = 100" in rows[0].claim and rows[0].paper == "12.3 % (linear)"


def test_report_gives_the_hertz_statistics_of_the_shipped_cubes(capsys):
    assert main(["report"]) == 0
    out = capsys.readouterr().out
    for name in HERTZ_CUBES:
        cube = xr.open_zarr(twoball.batch.cubes.cube_path(name), consolidated=False)
        height = f"{cube.attrs['height']:g}"
        h1, h2, icm = (cube[v].values.astype(float) for v in ("h1", "h2", "h_icm"))
        with np.errstate(invalid="ignore"):
            delayed = h2 > h1  # independently of the stored flag: float32 ties may differ
            below = h1 < icm
        found = {}
        for row, paper in (("share of the grid", "12.3"), ("of those", "93"),
                           ("of cases with h1 below", "22")):  # fmt: skip
            pattern = (rf"\| Hertz force, H = {height}: {row}[^|]*\| {paper} % \(linear\) \| "
                       r"[\d.]+ % \((\d+) of (\d+)\)")  # fmt: skip
            match = re.search(pattern, out)
            assert match, (name, row)
            found[row] = (int(match.group(1)), int(match.group(2)))
        assert found["share of the grid"][1] == delayed.size == 50**3
        assert abs(found["share of the grid"][0] - int(delayed.sum())) <= 5
        assert abs(found["of those"][0] - int((delayed & below).sum())) <= 5
        assert abs(found["of cases with h1 below"][1] - int(below.sum())) <= 5
        assert re.search(rf"\| Hertz force, H = {height}: where the delayed rebounds are \|", out)


@pytest.mark.slow
def test_a_hertz_sweep_killed_with_sigkill_resumes_to_the_same_cube(tmp_path):
    """As the linear sweep's test (tests/test_sweep.py), from the command line: killed part way
    with SIGKILL, run again, finished chunks untouched, the cube equal to one computed whole."""
    import os
    import signal
    import subprocess
    import sys
    import time

    grid = Grid(Axis("eps", 0.5, 1.0, 10), Axis("mu", 0.01, 1 / 3, 10),
                Axis("tau_ratio", 0.01, 1.0, 10), height=1e2, chunks=(1, 10, 10),
                force="hertz")  # fmt: skip
    store = tmp_path / "cube.zarr"
    command = [sys.executable, "-m", "twoball", "sweep", *grid.command(store).split()[2:],
               "--workers", "1", "--quiet"]  # fmt: skip
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    progress = store / "_progress"
    try:
        deadline = time.monotonic() + 300
        while time.monotonic() < deadline:
            if progress.is_dir() and len(list(progress.glob("*.*.*"))) >= 2:
                break
            time.sleep(0.005)
        os.kill(process.pid, signal.SIGKILL)
    finally:
        process.wait(timeout=60)
    finished = sorted(path.name for path in progress.glob("*.*.*"))
    assert 2 <= len(finished) < 10, "the run must be killed part way"
    written = {key: (store / "h1" / f"c.{key}").stat().st_mtime_ns for key in finished}
    again = subprocess.run(command, capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr
    for key, mtime in written.items():
        assert (store / "h1" / f"c.{key}").stat().st_mtime_ns == mtime
    cube = xr.open_zarr(store, consolidated=False).load()
    whole = compute_block(*(a.values() for a in grid.axes), height=grid.height)
    for name in VARIABLES:
        np.testing.assert_array_equal(cube[name].values, whole[name], name)


@pytest.mark.slow
def test_a_hertz_sweep_on_a_dask_cluster(tmp_path):
    from distributed import LocalCluster

    grid = _small(chunks=(1, 2, 3))
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster:  # fmt: skip
        cube = sweep(grid, tmp_path / "h.zarr", scheduler=cluster.scheduler_address,
                     progress=False).load()  # fmt: skip
    whole = compute_block(*(a.values() for a in grid.axes), height=grid.height)
    for name in VARIABLES:
        np.testing.assert_array_equal(cube[name].values, whole[name], name)


def test_where_names_the_corner_of_the_delayed_rebounds():
    from twoball.studies.hertz_report import where

    delayed = np.zeros((2, 2, 2), dtype=bool)
    delayed[1, 0, 0] = True  # eps 1, mu 0.01, tau_ratio 0.01 only
    ratio = np.full((2, 2, 2), 0.5)
    ratio[1, 0, 0] = 3.0
    dims = ("eps", "mu", "tau_ratio")
    cube = xr.Dataset(
        {"delayed_rebound": (dims, delayed), "h2_over_h1": (dims, ratio),
         "h1": (dims, np.ones((2, 2, 2)))},
        coords={"eps": [0.5, 1.0], "mu": [0.01, 0.3], "tau_ratio": [0.01, 1.0]},
    )  # fmt: skip
    text = where(cube)
    assert text.startswith("half at mu <= 0.01 (90 % <= 0.01), half at tau_ratio <= 0.01")
    assert "0.0 % at eps = 0.5 and 25.0 % at 1" in text
    assert "25.0 % at mu = 0.01 and 0.0 % at 0.3" in text
    assert text.endswith("largest h2/h1 3 at eps 1, mu 0.01, tau_ratio 0.01")
    assert where(cube.assign(delayed_rebound=(dims, np.zeros((2, 2, 2), bool)))) == "none"
