"""The command line: JSON output, and one line with exit status 2 for bad input."""

import json
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


def test_unknown_command_exits_2():
    completed = _run("fly")
    assert completed.returncode == 2 and len(completed.stderr.strip().splitlines()) == 1


def test_stack_json_matches_the_library():
    from twoball.stack import simulate_stack

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


def test_stack_bad_input_exits_2_naming_it():
    completed = _run("stack", "--mass-ratios", "0.3,0.1", "--eps", "0.8,0.7")
    assert completed.returncode == 2
    assert completed.stderr.strip() == (
        "twoball: error: eps must hold one value or 3 (the floor's, then each pair's); got 2"
    )
