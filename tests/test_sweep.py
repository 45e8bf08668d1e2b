"""Sweeps: the batch path against simulate and closed forms, shipped cubes regenerated, resume after
kill -9, refusal of a mismatched store, a real Dask LocalCluster, and bad command-line input."""

from __future__ import annotations

import contextlib
import json
import math
import os
import re
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from cases import BENIGN, CLOSE_UP
from scipy.optimize import brentq

import twoball
import twoball.batch.sweep
from twoball.batch.sweep import VARIABLES, Axis, Grid, compute_block, parse_axis, sweep
from twoball.cli import main
from twoball.observables import BALLS

OBSERVABLES = [name for name in VARIABLES if name != "status"]


def _same(a, b) -> bool:
    """Equal, with NaN equal to NaN and to None (a missing bounce)."""
    if b is None:
        return math.isnan(a)
    return bool(a == b) or (isinstance(b, float) and math.isnan(a) and math.isnan(b))


def test_block_matches_simulate_exactly():
    eps = [0.5, 0.816, 0.9, 1.0]
    mu = [0.001, 0.01, 0.05, 1 / 3]
    tau_ratio = [0.0, 0.01, 0.3, 2.0]
    block = compute_block(eps, mu, tau_ratio)
    for i, j, k in np.ndindex(4, 4, 4):
        summary = twoball.simulate(eps[i], mu[j], tau_ratio[k]).summary()
        summary["contacts_first"] = summary["contacts_first"][BALLS]  # a cube holds the balls'
        for name in OBSERVABLES:
            assert _same(block[name][i, j, k], summary[name]), (name, eps[i], mu[j], tau_ratio[k])


def test_block_check_values_of_model_md():
    block = compute_block([0.9, 0.816], [0.01, 0.05], [0.01, 0.3])
    assert block["h1"][0, 0, 0] == pytest.approx(CLOSE_UP.h1, abs=5e-6)  # as printed
    assert block["h2"][0, 0, 0] == pytest.approx(CLOSE_UP.h2, abs=5e-5)
    assert block["contacts_first"][0, 0, 0] == 4
    assert block["delayed_rebound"][0, 0, 0]
    assert block["h1"][1, 1, 1] == pytest.approx(BENIGN.h1, abs=5e-5)
    assert block["h2"][1, 1, 1] == pytest.approx(BENIGN.h2, abs=5e-5)
    assert not block["delayed_rebound"][1, 1, 1]
    assert (block["status"] == 0).all()


def _restitution_minus(r: float, eps: float) -> float:
    """eps(r) - eps for r < 1, written from docs/model.md, "Restitution and damping", independently
    of the package."""
    return math.exp(-r / math.sqrt(1 - r * r) * math.acos(2 * r * r - 1)) - eps


def test_block_icm_and_ratios_against_model_md_formulas():
    eps, mu, tau_ratio = np.array([0.6, 0.95]), np.array([0.02, 0.3]), np.array([0.1, 0.9])
    height = 1e3
    block = compute_block(eps, mu, tau_ratio, height=height)
    for i, j, k in np.ndindex(2, 2, 2):
        e, m = eps[i], mu[j]
        # tau_f and X2(0) from docs/model.md directly: r from eps(r) by brentq, not by the package
        r = brentq(_restitution_minus, 1e-12, 0.999, args=(e,))
        tau_f = math.acos(2 * r * r - 1) / math.sqrt(1 - r * r)
        x2_0 = (math.sqrt(height) + tau_ratio[k] * tau_f / math.sqrt(2)) ** 2
        gap = x2_0 - height
        h_icm = (height * (e * e + 2 * e - m) ** 2 + gap * (1 + m) * (m - e)) / (1 + m) ** 2
        assert block["x2_0"][i, j, k] == pytest.approx(x2_0, rel=1e-12)
        assert block["h_icm"][i, j, k] == pytest.approx(h_icm, rel=1e-10)
        h1, h2 = block["h1"][i, j, k], block["h2"][i, j, k]
        assert block["h1_over_icm"][i, j, k] == pytest.approx(h1 / h_icm, rel=1e-10)
        assert block["h2_over_drop"][i, j, k] == pytest.approx(h2 / x2_0, rel=1e-12)
        assert block["h2_over_h1"][i, j, k] == h2 / h1


def test_eps12_reaches_the_ball_contact():
    block = compute_block([0.8], [0.05], [0.3], eps12=0.6)
    result = twoball.simulate(0.8, 0.05, 0.3, eps12=0.6)
    assert block["h1"][0, 0, 0] == result.h1
    assert block["h_icm"][0, 0, 0] == pytest.approx(result.h_icm, rel=1e-14)
    assert block["h1"][0, 0, 0] != compute_block([0.8], [0.05], [0.3])["h1"][0, 0, 0]


def test_axes_spacing_and_parsing():
    log = parse_axis("mu", "1e-3:1:4:log").values()
    np.testing.assert_allclose(log, [1e-3, 1e-2, 1e-1, 1.0], rtol=1e-14)
    assert log[0] == 1e-3 and log[-1] == 1.0
    linear = parse_axis("mu", "0.01:1/3:50")
    assert linear.stop == 1 / 3 and linear.spacing == "linear"
    np.testing.assert_allclose(np.diff(linear.values()), (1 / 3 - 0.01) / 49, rtol=1e-12)
    assert parse_axis("eps", "0.816").values().tolist() == [0.816]
    grid = Grid(Axis("eps", 0.5, 1, 5), Axis("mu", 0.1, 0.2, 3), Axis("tau_ratio", 0, 1, 7),
                chunks=(2, 3, 4))  # fmt: skip
    slices = grid.chunk_slices()
    assert len(slices) == 3 * 1 * 2
    covered = np.zeros(grid.shape, dtype=int)
    for index in slices:
        covered[index] += 1
    assert (covered == 1).all()


SHIPPED = {
    # cube: (isel picking a small piece of it)
    "map": {"eps": [0, 13, 20], "mu": slice(0, None, 18), "tau_ratio": slice(3, None, 19)},
    "paper": {"eps": [0, 31, 49], "mu": slice(0, None, 16), "tau_ratio": slice(0, None, 12)},
    "contacts": {"eps": [0], "mu": slice(0, None, 37), "tau_ratio": slice(0, None, 40)},
}


@pytest.mark.parametrize("name", list(SHIPPED))
def test_shipped_cube_regenerates(name):
    cube = twoball.load_cube(name)
    assert cube.h1.chunks is not None  # opened lazily, as dask arrays
    assert tuple(cube.h1.dims) == ("eps", "mu", "tau_ratio")
    for variable in [*cube.data_vars, *cube.coords]:
        assert cube[variable].attrs["units"] and cube[variable].attrs["long_name"], variable
    for key in ("height", "grid", "solver", "twoball_version", "sweep_command", "precision"):
        assert key in cube.attrs
    command = (Path(twoball.batch.cubes.PRECOMPUTED) / f"{name}.cmd").read_text().split()
    assert command[:3] == ["twoball", "sweep", f"twoball/precomputed/{name}.zarr"]
    piece = cube.isel(SHIPPED[name]).load()
    arguments = json.loads(cube.attrs["sweep_arguments"])
    fresh = compute_block(
        piece.eps.values,
        piece.mu.values,
        piece.tau_ratio.values,
        height=cube.attrs["height"],
        eps12=arguments["eps12"],
    )
    for variable in VARIABLES:
        stored = piece[variable].values
        again = fresh[variable].astype(stored.dtype)
        if stored.dtype.kind != "f":
            np.testing.assert_array_equal(stored, again, variable)
            continue
        # to the stored precision: float32 rounding may flip by one unit if the solver's last
        # float64 bits move (the solver is exact to ~1e-13, float32 keeps ~6e-8)
        np.testing.assert_array_equal(np.isnan(stored), np.isnan(again), variable)
        finite = ~np.isnan(stored)
        np.testing.assert_array_max_ulp(stored[finite], again[finite], maxulp=1)


@pytest.mark.parametrize("name", ["paper", "map", "contacts", "hertz-h1e2", "hertz-h1e4"])
def test_cube_contacts_first_says_it_counts_the_ball_contacts_only(name):
    """A Result's contacts_first is [floor, ball]; the cube's holds the ball count alone, as
    floats (NaN: no first apex), and its attributes must say so to a reader of both."""
    variable = twoball.load_cube(name).contacts_first
    assert variable.dtype.kind == "f" and variable.attrs["units"] == "1"
    assert "ball-ball" in variable.attrs["long_name"]
    assert "contacts_first[1]" in variable.attrs["long_name"]
    description = variable.attrs["description"]
    assert "floor's contacts" in description and "not stored" in description
    assert "NaN" in description and "first apex" in description


def test_swept_contacts_first_is_the_results_ball_count_and_nan_without_a_first_apex(tmp_path):
    # eps = 0.02: the upper ball comes to rest on the lower one, with no first apex (NaN);
    # eps = 0.9: a first apex after one floor contact and one to four ball contacts
    store = tmp_path / "c.zarr"
    grid = Grid(Axis("eps", 0.02, 0.9, 2), Axis("mu", 0.01, 0.3, 2), Axis("tau_ratio", 0, 0.01, 2),
                height=100.0)  # fmt: skip
    sweep(grid, store, workers=1, progress=False)
    cube = twoball.load_cube(store).load()
    for eps, mu, tau_ratio in np.ndindex(grid.shape):
        cell = cube.isel(eps=eps, mu=mu, tau_ratio=tau_ratio)
        drop = (float(cell.eps), float(cell.mu), float(cell.tau_ratio))
        result = twoball.simulate(*drop, height=100.0, throw=False)
        if result.h1 is None:
            assert np.isnan(cell.contacts_first), drop
        else:
            assert cell.contacts_first == result.contacts_first[BALLS], drop


def test_map_cube_contract():
    cube = twoball.load_cube("map")
    assert set(VARIABLES) - {"status"} <= set(cube.data_vars)
    assert cube.attrs["height"] == 1e4
    eps = cube.eps.values
    assert eps[0] <= 0.5 and eps[-1] >= 1.0 and np.diff(eps).max() <= 0.025 + 1e-12
    for axis, low, high in (("mu", 1e-3, 1.0), ("tau_ratio", 1e-3, 10.0)):
        values = cube[axis].values
        assert values[0] <= low * (1 + 1e-12) and values[-1] >= high * (1 - 1e-12)
        ratios = values[1:] / values[:-1]
        np.testing.assert_allclose(ratios, ratios[0], rtol=1e-9)  # logarithmic
        assert 64 <= values.size <= 100
    assert cube.h1.chunks[0] == (1,) * eps.size  # one eps slice is one chunk
    assert cube.delayed_rebound.dtype == bool


def _grid(chunks=(1, 10, 40)) -> Grid:
    return Grid(
        Axis("eps", 0.5, 1.0, 12),
        Axis("mu", 1e-3, 1.0, 40, "log"),
        Axis("tau_ratio", 1e-3, 1.0, 40, "log"),
        height=1e3,
        chunks=chunks,
    )


def _assert_cube_equals_block(store: Path, grid: Grid) -> None:
    cube = xr.open_zarr(store, consolidated=False).load()
    whole = compute_block(*(a.values() for a in grid.axes), height=grid.height)
    for name in VARIABLES:
        np.testing.assert_array_equal(cube[name].values, whole[name], name)


def _sweep_command(store: Path, grid: Grid) -> list[str]:
    words = grid.command(store).split()[2:]
    return [sys.executable, "-m", "twoball", "sweep", *words, "--workers", "1"]


def _children(pid: int) -> list[int]:
    """Process ids whose parent is ``pid`` (Linux /proc)."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            with contextlib.suppress(OSError):
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
                if int(fields[1]) == pid:
                    found.append(int(entry.name))
    return found


@pytest.mark.slow
def test_resume_after_kill_9_finishes_without_recomputing(tmp_path):
    grid = _grid()
    store = tmp_path / "cube.zarr"
    total = len(grid.chunk_slices())
    process = subprocess.Popen(
        _sweep_command(store, grid),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    progress = store / "_progress"
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            if progress.is_dir() and len(list(progress.glob("*.*.*"))) >= 3:
                break
            time.sleep(0.01)
        # a local sweep computes in threads (the batch path releases the GIL): no worker
        # process is left behind when it is killed
        workers = _children(process.pid)
        os.kill(process.pid, signal.SIGKILL)
        process.wait(timeout=30)
    finally:
        with contextlib.suppress(ProcessLookupError):  # its workers, which we started too
            os.killpg(process.pid, signal.SIGKILL)
    assert process.returncode == -signal.SIGKILL
    assert workers == []
    finished = sorted(path.name for path in progress.glob("*.*.*"))
    assert 3 <= len(finished) < total, "the run must be killed part way"
    written = {key: (store / "h1" / f"c.{key}").stat().st_mtime_ns
               for key in finished}  # fmt: skip
    again = subprocess.run(_sweep_command(store, grid), capture_output=True, text=True, timeout=300)
    assert again.returncode == 0, again.stderr
    assert len(list(progress.glob("*.*.*"))) == total
    for key, mtime in written.items():  # finished chunks were not written again
        assert (store / "h1" / f"c.{key}").stat().st_mtime_ns == mtime
    _assert_cube_equals_block(store, grid)


def test_store_with_other_arguments_is_refused(tmp_path, capsys):
    small = Grid(Axis("eps", 0.8, 0.9, 2), Axis("mu", 0.1, 0.2, 2), Axis("tau_ratio", 0.1, 1, 3))
    store = tmp_path / "cube.zarr"
    sweep(small, store, workers=1, progress=False)
    metadata = (store / "zarr.json").read_bytes()
    chunk = (store / "h1" / "c.0.0.0").read_bytes()
    words = small.command(store).split()[2:]
    words[words.index("--height") + 1] = "1e3"
    assert main(["sweep", *words, "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "other arguments" in err and "height" in err
    assert (store / "zarr.json").read_bytes() == metadata
    assert (store / "h1" / "c.0.0.0").read_bytes() == chunk
    # the same arguments again: nothing left to do, nothing rewritten
    assert main(["sweep", *small.command(store).split()[2:], "--quiet"]) == 0
    assert (store / "h1" / "c.0.0.0").read_bytes() == chunk
    other = tmp_path / "not_a_cube"
    other.mkdir()
    (other / "precious.txt").write_text("keep me")
    with pytest.raises(ValueError, match="not a twoball sweep store"):
        sweep(small, other, workers=1, progress=False)
    assert (other / "precious.txt").read_text() == "keep me"


def test_leftover_of_a_run_killed_while_creating_is_cleared(tmp_path):
    small = Grid(Axis("eps", 0.8, 0.8, 1), Axis("mu", 0.1, 0.2, 2), Axis("tau_ratio", 0.1, 1, 2))
    store = tmp_path / "cube.zarr"
    (tmp_path / "cube.zarr.creating").mkdir()
    (tmp_path / "cube.zarr.creating" / "zarr.json").write_text("{truncated")
    sweep(small, store, workers=1, progress=False)
    assert not (tmp_path / "cube.zarr.creating").exists()
    _assert_cube_equals_block(store, small)
    cube = xr.open_zarr(store, consolidated=False)
    assert cube.h1.values[0, 1, 0] == twoball.simulate(0.8, 0.2, 0.1).h1


@pytest.mark.slow
def test_dask_local_cluster(tmp_path):
    from distributed import LocalCluster

    grid = _grid(chunks=(3, 20, 40))
    store = tmp_path / "cube.zarr"
    with LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=None,
    ) as cluster:
        worker_pids = {w.pid for w in cluster.workers.values()}
        assert len(worker_pids) == 2 and os.getpid() not in worker_pids
        sweep(grid, store, scheduler=cluster.scheduler_address, progress=False)
    _assert_cube_equals_block(store, grid)


@pytest.mark.parametrize(
    "words, named",
    [
        (["--eps", "0:1:5"], "eps"),
        (["--eps", "0.5:1.5:5"], "eps"),
        (["--mu", "0:1:5:log"], "mu"),
        (["--mu", "0.1:1:5:cubic"], "spacing"),
        (["--tau-ratio", "0:1:x"], "COUNT"),
        (["--tau-ratio", "1:0:3"], "stop"),
        (["--height", "-1"], "height"),
        (["--eps12", "2"], "eps12"),
        (["--chunks", "1,2"], "chunks"),
        (["--dtype", "float16"], "dtype"),
        (["--workers", "0"], "workers"),
        (["--eps", "abc"], "eps"),
    ],
)
def test_bad_arguments_exit_2_with_one_line(tmp_path, capsys, words, named):
    base = {"--eps": "0.5:1:3", "--mu": "0.01:0.3:3", "--tau-ratio": "0.1:1:3"}
    argv = ["sweep", str(tmp_path / "cube.zarr"), "--quiet"]
    given = dict(zip(words[::2], words[1::2], strict=True))
    for flag, value in {**base, **given}.items():
        argv += [flag, value]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("twoball: error:") and named in err
    assert "Traceback" not in err
    assert not (tmp_path / "cube.zarr").exists()


def test_unreachable_scheduler_exits_2_with_one_line(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(twoball.batch.sweep, "SCHEDULER_TIMEOUT", "1s")
    store = tmp_path / "cube.zarr"
    argv = ["sweep", str(store), "--eps", "0.8", "--mu", "0.1", "--tau-ratio", "0.1", "--quiet"]
    assert main([*argv, "--scheduler", "tcp://127.0.0.1:1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "scheduler" in err and "127.0.0.1:1" in err
    assert not store.exists()
    assert main([*argv, "--scheduler", "tcp://127.0.0.1:1", "--workers", "2"]) == 2
    assert "workers" in capsys.readouterr().err


def test_sweep_returns_the_cube_and_shows_progress_with_time_left(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    grid = Grid(Axis("eps", 0.7, 0.9, 3), Axis("mu", 0.05, 0.05, 1), Axis("tau_ratio", 0.2, 0.4, 2))
    cube = sweep(grid, Path("cube"), workers=1)  # a relative path without .zarr
    err = capsys.readouterr().err
    assert "100%" in err and re.search(r"6(\.00)?/6", err)
    assert re.search(r"\[\d\d:\d\d<\d\d:\d\d", err)  # elapsed<time left
    assert cube.h1.chunks is not None  # lazy
    point = cube.isel(eps=1, mu=0, tau_ratio=1)
    expected = twoball.simulate(float(point.eps), 0.05, 0.4).h1
    assert float(point.eps) == pytest.approx(0.8, rel=1e-15) and float(point.h1) == expected
    # the complete store has consolidated metadata: a plain open_zarr does not warn
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        reopened = xr.open_zarr(tmp_path / "cube")
    assert float(reopened.h1.isel(eps=1, mu=0, tau_ratio=1)) == expected


def test_the_batch_path_runs_the_same_as_plain_python_and_states_rest():
    """twoball.kernels.runs.run_block compiled (GIL released) and as its Python function (what runs
    while the kernels compile) give the same numbers, to rounding (numba's LAPACK and floating-point
    contraction differ from numpy's by ~1e-13); a drop that ends at rest says so in status."""
    from twoball import jit

    axes = ([0.05, 0.9], [0.01, 0.2], [0.01, 1.0])
    compiled = compute_block(*axes)
    jit.use_python_kernels()
    try:
        plain = compute_block(*axes)
    finally:
        jit.use_compiled_kernels()
    for name in OBSERVABLES:
        np.testing.assert_allclose(compiled[name], plain[name], rtol=1e-12, err_msg=name)
    rest = compiled["status"][0] == int(twoball.errors.Status.REST)
    assert rest.any() and np.isnan(compiled["h2"][0][rest]).all()
    assert (compiled["status"][1] == 0).all()


def test_default_chunks_are_whole_planes_of_about_chunk_drops():
    """Whole (mu, tau_ratio) planes, as many eps values a chunk as make ~CHUNK_DROPS drops,
    at least one and no more than the grid has."""
    from twoball.batch.sweep import CHUNK_DROPS

    def grid(eps: str, mu: str, tau_ratio: str) -> Grid:
        names = ("eps", "mu", "tau_ratio")
        return Grid(*(parse_axis(n, t) for n, t in zip(names, (eps, mu, tau_ratio), strict=True)))

    paper = grid("0.5:1:50", "0.01:1/3:50", "0.01:1:50")
    assert paper.chunks == (5, 50, 50) and CHUNK_DROPS == 5 * 50 * 50
    assert grid("0.5:1:3", "0.01:0.3:150", "0.01:1:100").chunks == (1, 150, 100)  # big planes
    assert grid("0.5:1:4", "0.01:0.3:10", "0.01:1:10").chunks == (4, 10, 10)  # the whole grid
    assert len(paper.chunk_slices()) == 10


def test_a_one_drop_plan_reads_as_one_drop():
    from twoball.batch.sweep import Grid, parse_axis, plan

    grid = Grid(parse_axis("eps", "0.9"), parse_axis("mu", "0.01"), parse_axis("tau_ratio", "0.1"))
    text = plan(grid, 2)
    assert text.startswith("1 drop (1 x 1 x 1), about 1 s on 2 workers (once the solver is")
    assert "at most 1 MB stored" in text and "0 s" not in text and "0 MB" not in text


def test_hertz_swept_contacts_first_is_nan_without_a_first_apex_as_the_linear_one():
    """The Hertz sweep stored a count of contacts for a drop with no first apex (eps = 0.05:
    the upper ball comes to rest), where the linear sweep and the cube's description say NaN;
    with a first apex it is the two-ball Hertz stack's ball-ball count."""
    from twoball.batch.hertz_sweep import compute_block
    from twoball.stacks import simulate_stack

    eps, mu, tau_ratio = np.array([0.05, 0.9]), np.array([0.3]), np.array([0.01])
    block = compute_block(eps, mu, tau_ratio, height=100.0)
    h1, contacts = block["h1"][:, 0, 0], block["contacts_first"][:, 0, 0]
    assert np.isnan(h1[0]) and np.isnan(contacts[0])
    stack = simulate_stack([0.3], 0.9, 0.01, height=100.0, force="hertz", until="second")
    assert h1[1] == pytest.approx(stack.h1, rel=1e-9)
    assert contacts[1] == stack.contacts_first[BALLS]
