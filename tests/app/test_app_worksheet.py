"""Worksheet downloads (app/worksheet.py): what a class takes home must be the drop and the map
on screen, checked against the solver called directly, not against the app's own output."""

from __future__ import annotations

import io

import numpy as np
import pytest
from bokeh.document import Document

import twoball
from app.explorer import Explorer
from app.map_slices import map_cube
from twoball import presets


def rendered(query: dict) -> Explorer:
    explorer = Explorer(query)
    explorer.__panel__().get_root(Document())
    return explorer


def read(text: str) -> tuple[dict[str, str], list[str], np.ndarray]:
    """(header values, column names, rows) of a worksheet file."""
    lines = text.splitlines()
    header = dict(line[2:].split(" = ", 1) for line in lines if line.startswith("# "))
    body = [line for line in lines if not line.startswith("#")]
    return header, body[0].split(","), np.loadtxt(io.StringIO("\n".join(body[1:])), delimiter=",")


@pytest.mark.parametrize("units", ["dimensionless", "SI"])
def test_the_drop_file_is_the_drop_on_screen(units):
    query = {"eps": "0.9", "mu": "0.01", "tau_ratio": "0.01", "units": units}
    scene = rendered(query).scenes["drop"]
    header, names, rows = read(scene.download.callback().getvalue())
    direct = twoball.simulate(0.9, 0.01, 0.01, dense_output=True)  # the same drop, called anew
    length = presets.length_scale() if units == "SI" else 1.0
    duration = presets.time_scale() if units == "SI" else 1.0
    force = presets.force_scale() if units == "SI" else 1.0
    assert float(header["h1"]) == pytest.approx(direct.h1 * length, rel=1e-12)
    assert float(header["h2"]) == pytest.approx(direct.h2 * length, rel=1e-12)
    assert header["delayed_rebound"] == "True" and header["ball_contacts_in_first_bounce"] == "4"
    assert names[0] == ("t [s]" if units == "SI" else "t") and len(names) == 7
    times = rows[:, 0] / duration
    state = direct.evaluate(times)
    for column, values, scale in (
        (1, state.x1, length), (2, state.x2, length), (3, state.v1, length / duration),
    ):  # fmt: skip
        assert np.allclose(rows[:, column], values * scale, rtol=1e-12, atol=1e-12 * scale)
    # the force jumps at a contact's start and end, which are rows of the file: a time written
    # in seconds and read back may land on either side, so there it is one side's value
    switches = np.array([t for c in direct.contacts for t in (c.start, c.end)])
    at_switch = np.min(np.abs(times[:, None] - switches[None, :]), axis=1) <= 1e-12 * times[-1]
    sides = [
        direct.evaluate(np.clip(times * (1 + side * 1e-12), 0, times[-1])).f12 * force
        for side in (-1, 1)
    ]
    # elsewhere the force's slope (up to 1e4 newtons a second) times the time's rounding
    # (an ulp of t in seconds, divided back by the time scale) is up to 1e-11 of it
    slack = 1e-12 if units == "dimensionless" else 1e-10
    assert np.allclose(
        rows[~at_switch, 6], state.f12[~at_switch] * force, rtol=slack, atol=slack * force
    )
    for row in np.flatnonzero(at_switch):
        jump = np.max(np.abs(rows[:, 6]))  # (each side moves by its slope in 1e-12 t)
        assert min(abs(rows[row, 6] - side[row]) for side in sides) <= 1e-6 * jump
    # the run to the second apex, both apexes among the rows
    assert times[-1] == pytest.approx(direct.t2, rel=1e-15)
    assert np.max(rows[:, 2]) == pytest.approx(direct.h2 * length, rel=1e-12)


def test_the_map_file_is_the_slice_on_screen():
    explorer = rendered({"eps": "0.83", "scene": "map"})
    scene = explorer.scenes["map"]
    header, names, rows = read(scene.download.callback().getvalue())
    cube = map_cube()
    assert names == ["mu", "tau_ratio", "h2_over_h1", "delayed_rebound"]
    assert len(rows) == cube.sizes["mu"] * cube.sizes["tau_ratio"]
    assert float(header["eps"]) == scene.slice_eps and header["source"] == "the shipped map cube"
    for row in rows[[100, 2500, 4000]]:
        mu, tau, ratio, delayed = row
        direct = twoball.simulate(scene.slice_eps, mu, tau, height=cube.attrs["height"])
        assert ratio == pytest.approx(direct.h2_over_h1, rel=1e-5)
        assert bool(delayed) == direct.delayed_rebound


@pytest.mark.browser
def test_a_click_downloads_the_drop_in_the_browser(browser, app_server, artifacts):
    from appdriver import open_page

    base, _ = app_server
    context, page, errors = open_page(browser, f"{base}/app?eps=0.9&mu=0.01&tau_ratio=0.01")
    try:
        with page.expect_download(timeout=30_000) as download:
            page.get_by_text("Download this drop (CSV)").click()
        saved = artifacts / "drop.csv"
        download.value.save_as(saved)
        header, names, rows = read(saved.read_text())
        assert float(header["h1"]) == pytest.approx(twoball.simulate(0.9, 0.01, 0.01).h1)
        assert names[:3] == ["t", "x1", "x2"] and len(rows) > 400
        assert errors == []
    finally:
        context.close()


def test_the_header_writes_a_parameter_as_a_link_does():
    """A worksheet's header read eps = 0.5700000000000001 (a slider's arithmetic, a teacher's
    trial): a parameter is written to 12 significant digits, as a link carries it; an old
    link's long mu keeps its 12 digits."""
    query = {"eps": "0.5700000000000001", "mu": "0.0446683592151", "tau_ratio": "0.01"}
    scene = rendered(query).scenes["drop"]
    header, _, _ = read(scene.download.callback().getvalue())
    assert header["eps"] == "0.57" and header["mu"] == "0.0446683592151"
    assert header["tau_ratio"] == "0.01" and header["eps12"] == "0.57"  # (equal to eps)
