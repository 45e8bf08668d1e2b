"""The command line: JSON output, and one line with exit status 2 for bad input."""

import json
import os
import re
import subprocess
import sys

import pytest

import twoball


def _run(*arguments):
    return subprocess.run(
        [sys.executable, "-m", "twoball", *arguments], capture_output=True, text=True, timeout=120
    )


def test_simulate_json_matches_the_library():
    completed = _run("simulate", "--eps", "0.9", "--mu", "0.01", "--tau-ratio", "0.01", "--json")
    assert completed.returncode == 0, completed.stderr
    data = json.loads(completed.stdout)
    result = twoball.simulate(0.9, 0.01, 0.01)
    for key in ("h1", "h2", "t1", "t2", "contacts_first", "h_icm", "x2_0"):
        assert data[key] == getattr(result, key)


def test_missing_bounce_is_null_in_json():
    completed = _run(
        "simulate", "--eps", "0.02", "--mu", "0.3", "--tau-ratio", "0", "--height", "100", "--json"
    )
    data = json.loads(completed.stdout)
    assert data["h2"] is None and data["t2"] is None and "rest" in data["reason"]


@pytest.mark.parametrize(
    ("arguments", "named"),
    [
        (["--eps", "abc", "--mu", "0.1", "--tau-ratio", "0.3"], "eps"),
        (["--eps", "0.8", "--mu", "-1", "--tau-ratio", "0.3"], "mu"),
        (["--eps", "1.5", "--mu", "0.1", "--tau-ratio", "0.3"], "eps"),
        (["--eps", "0.8", "--mu", "0.1", "--tau-ratio", "nan"], "tau_ratio"),
        (["--eps", "0.8", "--mu", "0.1", "--tau-ratio", "0.3", "--height", "0"], "height"),
        (["--eps", "0.8", "--mu", "0.1", "--tau-ratio", "0.3", "--eps12", "2"], "eps12"),
        (["--eps", "0.8", "--mu", "0.1", "--tau-ratio", "0.3", "--method", "euler"], "method"),
        (["--eps", "0.8"], "--mu"),
    ],
)
def test_bad_input_exits_2_with_one_line(arguments, named):
    completed = _run("simulate", *arguments)
    assert completed.returncode == 2
    lines = completed.stderr.strip().splitlines()
    assert len(lines) == 1 and named in lines[0]
    assert "Traceback" not in completed.stderr and completed.stdout == ""


def test_many_contacts_bad_seed_exits_2_naming_it(tmp_path):
    completed = _run("many-contacts", "--out", str(tmp_path), "--seed", "-1")
    lines = completed.stderr.strip().splitlines()
    assert completed.returncode == 2 and len(lines) == 1 and "--seed" in lines[0]
    assert not any(tmp_path.iterdir())  # nothing written


def test_a_reader_that_stops_early_gets_no_traceback(monkeypatch):
    """twoball simulate ... | head: the pipe closes before the summary is written; the command
    ends quietly with SIGPIPE's status (it printed a BrokenPipeError traceback)."""
    import io

    from twoball import cli

    read_end, write_end = os.pipe()
    os.close(read_end)
    stdout = io.TextIOWrapper(os.fdopen(write_end, "wb"), write_through=True)
    monkeypatch.setattr(sys, "stdout", stdout)
    try:
        status = cli.main(["simulate", "--eps", "0.9", "--mu", "0.01", "--tau-ratio", "0.01"])
    finally:
        monkeypatch.undo()
    assert status == 141


def test_unknown_command_exits_2():
    completed = _run("fly")
    assert completed.returncode == 2 and len(completed.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize(
    ("arguments", "named"),
    [
        (["simulate", "--bogus"], "--bogus"),  # (named before the required ones missing)
        (["simulate", "--eps", "0.9", "--mu", "0.01", "--tau_ratio", "0.01"], "--tau_ratio"),
        (["simulate", "--eps", "0.9", "--mu", "0.01", "--tau-ratio", "0.01", "--x=1"], "--x"),
    ],
)
def test_an_unknown_option_is_named(arguments, named):
    line = _one_line_error(_run(*arguments))
    assert f"unrecognized arguments: {named}" in line, line


def test_abbreviations_and_negative_values_are_not_unknown():
    """argparse takes an option's abbreviation (--tau for --tau-ratio) and a negative value:
    neither is named unknown; the refused value is."""
    line = _one_line_error(_run("simulate", "--eps", "-0.5", "--mu", "0.01", "--tau", "0.01"))
    assert "unrecognized" not in line and "eps must be" in line, line


def test_stack_json_matches_the_library():
    from twoball.stacks import simulate_stack

    completed = _run(
        "stack", "--mass-ratios", "0.3,0.1", "--eps", "0.8,0.7,0.9", "--tau-ratios", "0.5,0.1",
        "--json",
    )  # fmt: skip
    assert completed.returncode == 0, completed.stderr
    data = json.loads(completed.stdout)
    result = simulate_stack([0.3, 0.1], [0.8, 0.7, 0.9], [0.5, 0.1])
    assert (data["h1"], data["h2"]) == (result.h1, result.h2)
    assert data["contacts_first"] == result.contacts_first and data["balls"] == 3
    assert data["h1_over_icm"] == result.h1 / result.h_icm
    # the observables' keys are simulate's (a finished run's reason null, as simulate's)
    assert set(result.measured()) <= set(data) and data["reason"] is None


def test_stack_bad_input_exits_2_naming_it():
    from twoball.stacks import simulate_stack

    completed = _run("stack", "--mass-ratios", "0.3,0.1", "--eps", "0.8,0.7")
    assert completed.returncode == 2
    assert completed.stderr.strip() == (
        "twoball: error: eps must be one number or a flat sequence of exactly 3 (the floor's, "
        "then each pair's: 3 balls); got a sequence of 2"
    )
    # one value on the command line stands for every contact, as the help says
    completed = _run("stack", "--mass-ratios", "0.3,0.1", "--eps", "0.8", "--json")
    assert completed.returncode == 0, completed.stderr
    assert json.loads(completed.stdout)["h2"] == simulate_stack([0.3, 0.1], [0.8] * 3, 0.2).h2


def _one_line_error(completed, status=2):
    assert completed.returncode == status, (completed.stdout, completed.stderr)
    assert "Traceback" not in completed.stderr
    lines = completed.stderr.strip().splitlines()
    assert len(lines) == 1, completed.stderr
    return lines[0]


def test_version():
    completed = _run("--version")
    assert (
        completed.returncode == 0 and completed.stdout.strip() == f"twoball {twoball.__version__}"
    )


def test_help_states_the_enforced_ranges():
    """The help said eps in (0, 1] and mu > 0 while [0.01, 1] and [1e-9, 1e6] were enforced."""
    from twoball.model import Parameters

    text = " ".join(_run("simulate", "--help").stdout.split())
    low, high = Parameters.param["eps"].bounds
    assert f"eps in [{low:g}, {high:g}]" in text
    low, high = Parameters.param["mu"].bounds
    assert f"m2/m1 in [{low:g}, {high:g}]" in text
    assert "(0, 1]" not in text and "> 0" not in text
    stack = " ".join(_run("stack", "--help").stdout.split())
    assert "one restitution in [0.01, 1]" in stack and "products in [1e-09, 1e+06]" in stack
    doc = " ".join(twoball.simulate.__doc__.split())
    assert "in [0.01, 1]" in doc and "in [1e-09, 1e+06]" in doc and "(0, 1]" not in doc


def _option_help(command: str, option: str) -> str:
    """The help of one option of a command, on one line."""
    options = " ".join(_run(command, "--help").stdout.split()).split(" options: ", 1)[1]
    return options.split(f" {option} ", 1)[1].split(" --", 1)[0]


@pytest.mark.parametrize("command", ["simulate", "sweep"])
@pytest.mark.parametrize(
    ("option", "parameter", "refused"),
    [("--eps", "eps", 2.0), ("--mu", "mu", 0.0), ("--tau-ratio", "tau_ratio", -1.0)],
)
def test_each_parameters_help_gives_the_range_its_error_gives(command, option, parameter, refused):
    """sweep --tau-ratio (and --eps, --mu) said nothing of the range the library enforces."""
    drop = {"eps": 0.9, "mu": 0.1, "tau_ratio": 0.3, parameter: refused}
    with pytest.raises(ValueError, match=parameter) as refusal:
        twoball.simulate(**drop)
    allowed = re.search(r" in ([\[(][^;]*); got", str(refusal.value)).group(1)
    assert f" in {allowed}" in _option_help(command, option)


def test_until_names_what_it_takes():
    line = _one_line_error(
        _run("simulate", "--eps", "0.9", "--mu", "0.01", "--tau-ratio", "0.01", "--until", "third")
    )
    assert "--until" in line and "first, second or a time" in line


def test_a_run_to_a_time_before_the_apexes_says_why_they_are_missing():
    completed = _run(
        "simulate", "--eps", "0.9", "--mu", "0.01", "--tau-ratio", "0.01", "--until", "100"
    )
    assert completed.returncode == 0, completed.stderr
    reason = [line for line in completed.stdout.splitlines() if line.startswith("reason")]
    assert reason and "no apex of the upper ball before t = 100" in reason[0]
    assert twoball.simulate(0.9, 0.01, 0.01, until=100.0).apex_h == []  # and truly none


def test_stack_beyond_the_domain_exits_2_with_one_line():
    """twoball stack --height 1e30 printed h1 = 2.3e30 (linear) or a traceback (hertz)."""
    for force in ("linear", "hertz"):
        line = _one_line_error(
            _run("stack", "--mass-ratios", "0.2", "--height", "1e30", "--force", force)
        )
        assert "height must be at most" in line


@pytest.mark.parametrize("store", [".", "", "/", ".."])
def test_a_sweep_store_must_be_named(store, tmp_path):
    completed = subprocess.run(
        [sys.executable, "-m", "twoball", "sweep", store, "--eps", "0.9", "--mu", "0.1",
         "--tau-ratio", "0.1", "--quiet"],
        capture_output=True, text=True, timeout=120, cwd=tmp_path,
    )  # fmt: skip
    assert "store" in _one_line_error(completed)
    assert list(tmp_path.iterdir()) == []


def test_a_sweep_that_cannot_write_names_the_store_given(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    store = str(blocker / "x.zarr")
    line = _one_line_error(
        _run("sweep", store, "--eps", "0.9", "--mu", "0.1", "--tau-ratio", "0.1", "--quiet")
    )
    assert line.endswith(f"{store}: the directory it goes in, {blocker}, is not a directory")


def test_a_sweep_makes_its_store_not_the_directories_above_it(tmp_path):
    """A mistyped path made every missing directory above the store, silently."""
    store = tmp_path / "missing" / "dir" / "x.zarr"
    line = _one_line_error(
        _run("sweep", str(store), "--eps", "0.9", "--mu", "0.1", "--tau-ratio", "0.1", "--quiet")
    )
    assert f"{tmp_path / 'missing' / 'dir'}, does not exist (make it first)" in line
    assert list(tmp_path.iterdir()) == []


def test_report_on_an_array_inside_a_store_is_one_line(tmp_path):
    store = tmp_path / "small.zarr"
    made = _run(
        "sweep", str(store), "--eps", "0.8:0.9:2", "--mu", "0.1", "--tau-ratio", "0.1", "--quiet"
    )
    assert made.returncode == 0, made.stderr
    line = _one_line_error(_run("report", "--paper-cube", str(store / "h1")))
    assert "array inside a store" in line and "h1" in line
    # the store itself, too small for the paper's claims: one line, not a numpy traceback
    line = _one_line_error(_run("report", "--paper-cube", str(store)))
    assert "must reach tau_ratio above 0.85" in line and "0.1 to 0.1" in line


def test_a_hertz_integrator_failure_is_one_line_and_status_1(monkeypatch, capsys):
    """DOP853 (the Hertz reference method) failing in a contact phase printed a RuntimeError
    traceback (exit 1)."""
    from twoball import cli
    from twoball.stacks import hertz

    class Failing(hertz.DOP853):
        def step(self):
            self.status = "failed"
            return "Required step size is less than spacing between numbers."

    monkeypatch.setattr(hertz, "DOP853", Failing)
    command = ["stack", "--mass-ratios", "0.2", "--force", "hertz", "--method", "DOP853"]
    assert cli.main(command) == 1
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("twoball: solver failed:")
    assert "integrator failed" in lines[0]


def test_many_contacts_without_the_studies_extra_is_one_line(tmp_path):
    """Without mpmath the worker processes printed their tracebacks."""
    fake = tmp_path / "mpmath"
    fake.mkdir()
    (fake / "__init__.py").write_text(
        'raise ModuleNotFoundError("No module named \'mpmath\'", name="mpmath")\n'
    )
    environment = {**os.environ, "PYTHONPATH": str(tmp_path)}
    completed = subprocess.run(
        [sys.executable, "-m", "twoball", "many-contacts", "--out", str(tmp_path / "mc"),
         "--count", "1"],
        capture_output=True, text=True, timeout=120, env=environment,
    )  # fmt: skip
    line = _one_line_error(completed)
    assert "'studies' extra" in line


def test_a_stack_run_to_a_time_before_the_top_balls_apexes_says_why():
    """The top ball of this stack first rises to h1 after t = 500 (the library says when), so
    a run to t = 500 has no apex of it, and says so."""
    from twoball.stacks import simulate_stack

    assert simulate_stack([0.2, 0.2], 0.9, 0.2).apexes[-1][0][0] > 500  # the premise
    completed = _run("stack", "--mass-ratios", "0.2,0.2", "--until", "500")
    assert completed.returncode == 0, completed.stderr
    reason = [line for line in completed.stdout.splitlines() if line.startswith("reason")]
    assert reason and "no apex of the top ball before t = 500" in reason[0]
    finished = _run("stack", "--mass-ratios", "0.2,0.2")
    assert not [line for line in finished.stdout.splitlines() if line.startswith("reason")]


def test_a_first_use_says_the_solver_is_compiling(monkeypatch, tmp_path, capsys):
    """With no machine code of the command's kernels on disk, one line on stderr says that the
    first run compiles; with it there, nothing is said (jit.compiled_on_disk reads the cache)."""
    from twoball import cli, jit

    monkeypatch.setattr(jit, "CACHE_DIR", tmp_path)
    assert not jit.compiled_on_disk("twoball.kernels.runs")
    assert cli.main(["simulate", "--eps", "0.9", "--mu", "0.01", "--tau-ratio", "0.01"]) == 0
    said = capsys.readouterr().err.splitlines()
    assert len(said) == 1 and "compiling the solver" in said[0]
    for module, argv in (
        ("runs", ["simulate", "--eps", "0.9", "--mu", "0.01", "--tau-ratio", "0.01"]),
        ("stack", ["stack", "--mass-ratios", "0.2,0.2", "--eps", "0.9"]),
    ):
        (tmp_path / "twoball" / "kernels").mkdir(parents=True, exist_ok=True)
        (tmp_path / "twoball" / "kernels" / f"{module}.run-12.py311.nbi").write_bytes(b"")
        assert cli.main(argv) == 0
        assert capsys.readouterr().err == ""
    assert not jit.compiled_on_disk("twoball.kernels.hertz")


@pytest.mark.parametrize(
    "argv",
    [
        ["simulate", "--eps", "5", "--mu", "0.01", "--tau-ratio", "0.01"],
        ["stack", "--mass-ratios", "0.2,0.2", "--eps", "0.9,0.9"],
        ["stack", "--mass-ratios", "0.2", "--method", "DOP853"],
        ["stack", "--mass-ratios", "0.2", "--tau-ratios", "1e300"],
        ["sweep", "STORE", "--eps", "0.5:5:3", "--mu", "0.1", "--tau-ratio", "0"],
    ],
)
@pytest.mark.filterwarnings("error")  # (a warning printed is a line more: overflow, 1e300)
def test_a_refused_parameter_on_a_first_use_is_the_only_line(monkeypatch, tmp_path, capsys, argv):
    """Nothing compiled yet and a parameter refused: the error is the one line on stderr (the
    compiling notice came first, for a run that was never to start)."""
    from twoball import cli, jit

    monkeypatch.setattr(jit, "CACHE_DIR", tmp_path)
    store = tmp_path / "cube.zarr"
    assert cli.main([str(store) if word == "STORE" else word for word in argv]) == 2
    said = capsys.readouterr().err.splitlines()
    assert len(said) == 1 and said[0].startswith("twoball: error:"), said
    assert not store.exists()


def test_serve_help_without_the_app_extra_says_what_to_install(tmp_path):
    """Without Panel, ``twoball serve --help`` still helps (status 0, what to install); serving
    itself says which extra it needs, in one line, status 2."""
    fake = tmp_path / "panel"
    fake.mkdir()
    (fake / "__init__.py").write_text(
        'raise ModuleNotFoundError("No module named \'panel\'", name="panel")\n'
    )
    environment = {**os.environ, "PYTHONPATH": str(tmp_path)}
    run = [sys.executable, "-m", "twoball", "serve"]
    helped = subprocess.run(
        [*run, "--help"], capture_output=True, text=True, timeout=120, env=environment
    )
    assert helped.returncode == 0 and helped.stderr == ""
    assert "usage: twoball serve" in helped.stdout and "pip install 'twoball[app]'" in helped.stdout
    served = subprocess.run(run, capture_output=True, text=True, timeout=120, env=environment)
    assert "'app' extra" in _one_line_error(served)


def test_json_output_is_strict_json(capsys):
    """A value that is not a number (nan, inf) goes out as null: Python's NaN is not JSON, and
    jq or a browser's JSON.parse refused the line (a researcher's trial)."""
    from twoball import cli

    cli._print_summary({"h_icm": float("nan"), "apexes": [1.5, float("inf")], "n": 2}, True)
    line = capsys.readouterr().out
    parsed = json.loads(line, parse_constant=lambda name: pytest.fail(f"{name} in {line}"))
    assert parsed == {"h_icm": None, "apexes": [1.5, None], "n": 2}
