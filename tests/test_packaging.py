"""How users install twoball: a plain (non-editable) wheel in a fresh virtual environment, used
from another directory, first with the core dependencies only, then with the extras; and where
numba's cache goes when the usual places cannot be written."""

from __future__ import annotations

import fcntl
import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
EXTRA_MODULES = ("xarray", "zarr", "dask", "tqdm", "matplotlib", "mpmath", "panel", "holoviews")


def test_import_twoball_loads_no_extra():
    code = (
        "import json, sys, twoball; twoball.simulate(0.9, 0.01, 0.01);"
        f"print(json.dumps([m for m in {EXTRA_MODULES!r} if m in sys.modules]))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert json.loads(out.stdout) == []


def _run(command: list[str], cwd: Path, **options) -> subprocess.CompletedProcess:
    environment = {k: v for k, v in os.environ.items() if k not in ("VIRTUAL_ENV", "PYTHONPATH")}
    return subprocess.run(
        command, cwd=cwd, capture_output=True, text=True, env=environment, timeout=900, **options
    )


@pytest.mark.slow
def test_plain_wheel_works_from_another_directory(tmp_path):
    wheels = tmp_path / "wheels"
    built = _run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "-v", "-w", str(wheels), "."], REPO
    )
    assert built.returncode == 0, built.stderr
    # setuptools warned of twoball.precomputed and twoball_app.static, data directories left
    # out of `packages` (its -v output)
    assert "absent from the `packages` configuration" not in built.stdout + built.stderr
    (wheel,) = wheels.glob("twoball-*.whl")
    # every shipped cube's file and every script of the app's static/ is in the wheel
    data = {"twoball/precomputed": REPO / "twoball" / "precomputed",
            "twoball_app/static": REPO / "app" / "static"}  # fmt: skip
    shipped = {
        f"{package}/{path.relative_to(folder).as_posix()}"
        for package, folder in data.items()
        for path in folder.rglob("*")
        if path.is_file()
    }
    assert len(shipped) > 2000 and shipped <= set(zipfile.ZipFile(wheel).namelist())
    venv = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", str(venv)], tmp_path, check=True)
    python, pins = str(venv / "bin" / "python"), str(REPO / "requirements" / "test.txt")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()

    core = _run([python, "-m", "pip", "install", "-q", "-c", pins, str(wheel)], elsewhere)
    assert core.returncode == 0, core.stderr
    drop = _run([str(venv / "bin" / "twoball"), "simulate", "--eps", "0.9", "--mu", "0.01",
                 "--tau-ratio", "0.01", "--json"], elsewhere)  # fmt: skip
    assert drop.returncode == 0, drop.stderr
    assert abs(json.loads(drop.stdout)["h1"] - 9256.04845) < 1e-4  # docs/model.md check value
    # a command that needs an extra says which, in one line, with status 2
    report = _run([str(venv / "bin" / "twoball"), "report"], elsewhere)
    assert report.returncode == 2
    assert report.stderr.count("\n") == 1 and "pip install 'twoball[sweep]'" in report.stderr

    extras = _run(
        [python, "-m", "pip", "install", "-q", "-c", pins, f"{wheel}[sweep,studies]"], elsewhere
    )
    assert extras.returncode == 0, extras.stderr
    code = (
        "import twoball; cube = twoball.load_cube('map'); print(twoball.__file__);"
        "print(cube.sizes['eps'] * cube.sizes['mu'] * cube.sizes['tau_ratio'])"
    )
    cube = _run([python, "-c", code], elsewhere)
    assert cube.returncode == 0, cube.stderr
    location, size = cube.stdout.split()
    assert Path(location).is_relative_to(venv) and int(size) == 21 * 73 * 81
    report = _run([str(venv / "bin" / "twoball"), "report"], elsewhere)
    assert report.returncode == 0, report.stderr
    assert "delayed rebound" in report.stdout.lower()


def test_unwritable_cache_directory_is_not_fatal(tmp_path):
    """A NUMBA_CACHE_DIR that cannot be written (here: below a file, which even root cannot
    write) makes twoball use a private directory; before, declaring the kernels failed with
    "cannot cache function ...: no locator available". The Docker tests do this for real."""
    blocker = tmp_path / "file"
    blocker.write_text("")
    code = (
        "import twoball; from numba.core import config; from twoball import jit;"
        "print(jit.CACHE_DIR, config.CACHE_DIR)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code],
        env={**os.environ, "NUMBA_CACHE_DIR": str(blocker / "cache"), "TMPDIR": str(tmp_path)},
        capture_output=True,
        text=True,
    )
    assert out.returncode == 0, out.stderr
    chosen, configured = out.stdout.split()
    # a private directory, in it the subdirectory of these sources (twoball.jit.sources_key)
    assert chosen == configured and Path(chosen).parent.parent == tmp_path


def test_prebuilt_cache_that_cannot_be_written_is_copied(tmp_path, monkeypatch):
    from twoball import jit

    prebuilt = tmp_path / "prebuilt"
    (prebuilt / "kernels").mkdir(parents=True)
    (prebuilt / "kernels" / "exact.nbi").write_text("index")
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(prebuilt))
    monkeypatch.setenv("TMPDIR", str(tmp_path / "tmp"))
    monkeypatch.setattr(jit.tempfile, "tempdir", None)  # gettempdir() reads TMPDIR again
    (tmp_path / "tmp").mkdir()
    writable = jit._writable
    monkeypatch.setattr(jit, "_writable", lambda path: path != prebuilt and writable(path))
    chosen = jit.choose_cache_dir()
    assert chosen.parent == tmp_path / "tmp"
    assert (chosen / "kernels" / "exact.nbi").read_text() == "index"


def test_the_kernel_cache_is_keyed_on_every_kernel_module(tmp_path, monkeypatch):
    """An edit to any kernel module (here twoball/kernels/stack.py, whose kernels carry the code of
    twoball/kernels/phases.py's) moves the disk cache to a fresh directory: numba itself would check
    only the timestamp of each kernel's own file and serve stale code of the modules it calls."""
    from twoball import jit

    for name in jit.KERNEL_MODULES:
        copy = tmp_path / jit.source_of(name).relative_to(jit.PACKAGE)
        copy.parent.mkdir(parents=True, exist_ok=True)
        copy.write_bytes(jit.source_of(name).read_bytes())
    monkeypatch.setattr(jit, "PACKAGE", tmp_path)
    before = jit.sources_key()
    assert jit.CACHE_DIR is False or Path(jit.CACHE_DIR).name == before
    with open(tmp_path / "kernels" / "stack.py", "a") as handle:
        handle.write("\n# an edit\n")
    assert jit.sources_key() != before


def test_a_child_process_uses_the_parents_kernel_cache(tmp_path):
    """compile_in_background fills the cache from a child process, which inherits the
    NUMBA_CACHE_DIR this process set (the keyed directory): it must use that directory, not
    one keyed again inside it, or the server finds nothing and compiles everything itself (a
    first start took 130 s instead of ~40, and a page served meanwhile asked a CDN for Panel's
    stylesheets)."""
    code = "from twoball import jit; print(jit.CACHE_DIR)"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    parent = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert parent.returncode == 0, parent.stderr
    keyed = parent.stdout.strip()
    assert Path(keyed).parent == tmp_path / "cache"
    child = subprocess.run(
        [sys.executable, "-c", code],
        env={**os.environ, "NUMBA_CACHE_DIR": keyed},
        capture_output=True,
        text=True,
    )
    assert child.returncode == 0, child.stderr
    assert child.stdout.strip() == keyed


def test_one_compiler_at_a_time_per_cache():
    """The processes of ``twoball serve --num-procs N`` start together on a new machine: their
    compilers take turns on the cache (a lock file in it), so a second one waits without using
    a core and then finds the machine code there. Holding the lock here, a server's compiler
    must wait; released, it finishes."""
    from twoball import jit

    if not isinstance(jit.CACHE_DIR, Path):
        pytest.skip("no disk cache can be written here, so no compiler process to serialise")
    jit.CACHE_DIR.mkdir(parents=True, exist_ok=True)
    script = (
        "from twoball import jit, warmup\n"
        "thread = warmup.compile_in_background()\n"
        "thread.join(timeout=6)\n"
        "print(jit.state, flush=True)\n"
        "thread.join(timeout=300)\n"
        "print(jit.state, flush=True)\n"
    )
    env = {**os.environ, "NUMBA_CACHE_DIR": str(jit.CACHE_DIR)}
    with open(jit.CACHE_DIR / "compiling.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        server = subprocess.Popen(
            [sys.executable, "-c", script], env=env, stdout=subprocess.PIPE, text=True
        )
        assert server.stdout.readline().strip() == "compiling"  # waiting for the lock
    assert server.stdout.readline().strip() == "compiled"
    assert server.wait(timeout=60) == 0


def test_the_python_stand_ins_are_all_put_back():
    """A first start runs the kernels' Python functions while the compiler works, then puts
    the compiled kernels back (twoball.jit). In a fresh process, where no kernel module was
    imported yet, every module must have its compiled kernels again afterwards, those it
    imports from another module too: hertz's ``force_bounds`` stayed a Python function, and a
    first start with a cold cache failed to compile the Hertz kernel and stayed on Python
    kernels ("Untyped global name 'force_bounds'")."""
    code = (
        "import importlib, sys\n"
        "from numba.core.registry import CPUDispatcher\n"
        "from twoball import jit\n"
        "assert 'twoball.kernels.hertz' not in sys.modules\n"
        "jit.use_python_kernels(); jit.use_compiled_kernels()\n"
        "modules = [importlib.import_module(name) for name in jit.KERNEL_MODULES]\n"
        "kernels = [v for m in modules for v in vars(m).values() if isinstance(v, CPUDispatcher)]\n"
        "stand_ins = {id(k.py_func) for k in kernels}\n"
        "left = [(m.__name__, a) for m in modules for a, v in vars(m).items()\n"
        "        if id(v) in stand_ins]\n"
        "print(len(kernels), left)\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    count, left = run.stdout.split(" ", 1)
    assert int(count) > 50 and left.strip() == "[]", run.stdout


def test_each_compile_stage_holds_the_kernels_its_kernels_call():
    """The first start puts the compiled kernels back stage by stage (twoball.warmup.STAGES),
    the two-ball solver's first. A module put back while a kernel its kernels call is still a
    Python stand-in would compile against the stand-in and fail: every kernel a stage's module
    names is defined in that stage or an earlier one, and the stages hold every module once."""
    import importlib

    from numba.core.registry import CPUDispatcher

    from twoball import jit, warmup

    staged = [module for _, modules, _ in warmup.STAGES for module in modules]
    assert sorted(staged) == sorted(jit.KERNEL_MODULES)
    ready: set[str] = set()
    for _, modules, _ in warmup.STAGES:
        ready.update(modules)
        for name in modules:
            for attribute, value in vars(importlib.import_module(name)).items():
                if isinstance(value, CPUDispatcher):
                    assert value.py_func.__module__ in ready, (name, attribute)


def test_the_two_ball_kernels_come_back_before_the_stacks():
    """While the stacks' kernels still compile, the two-ball solver's run as machine code and
    the stack's Python stand-ins still give the stack's results (checked against the same
    stack once everything is compiled); then everything is compiled."""
    script = (
        "from twoball import jit, warmup\n"
        "from twoball.stacks import simulate_stack\n"
        "import twoball\n"
        "def staged(stage):\n"
        "    if stage == 'two-ball':\n"
        "        stack = simulate_stack([0.2, 0.2], 0.9, 0.2)\n"
        "        print(stage, jit.compiled('twoball.kernels.runs'),\n"
        "              jit.compiled('twoball.kernels.stack'), jit.state, stack.h2, flush=True)\n"
        "thread = warmup.compile_in_background(staged=staged)\n"
        "thread.join(timeout=900)\n"
        "print(jit.state, simulate_stack([0.2, 0.2], 0.9, 0.2).h2, flush=True)\n"
    )
    run = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=1200
    )
    assert run.returncode == 0, run.stderr[-3000:]
    first, last = run.stdout.splitlines()
    stage, runs, stack, state, h2_python = first.split()
    assert (stage, runs, stack, state) == ("two-ball", "True", "False", "compiling"), first
    final_state, h2_compiled = last.split()
    assert final_state == "compiled"
    assert abs(float(h2_python) - float(h2_compiled)) <= 1e-9 * abs(float(h2_compiled)), run.stdout
