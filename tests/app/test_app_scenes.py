"""The scenes without a browser: what each computes, when, and that it is right.

Values are checked against model.md's check values and against the exact solver called
directly (for the map's cube slice), not against the app's own earlier output.
"""

from __future__ import annotations

import math
import re

import numpy as np
import panel as pn
import param
import pytest
from bokeh.document import Document

import twoball
from app.collisions import collisions
from app.drop import TRAILS
from app.explorer import Explorer, page_shell
from app.map_slices import map_cube
from app.scene import Scene
from app.scenes import SCENE_REGISTRY, SCENES
from app.state import ExplorerState, metres_text, url_query
from twoball import ParameterError, presets
from twoball.observables import BALLS, FLOOR
from twoball.stacks import simulate_stack
from twoball.units import number_text

PAPER = {"eps": "0.9", "mu": "0.01", "tau_ratio": "0.01"}


def rendered(query: dict | None = None) -> Explorer:
    explorer = Explorer(query or {})
    explorer.__panel__().get_root(Document())
    return explorer


def computations(explorer: Explorer) -> dict[str, int]:
    """How often each scene computed (0 for a scene not built yet)."""
    built = explorer.scenes
    return {name: built[name].computations if name in built else 0 for name in SCENE_REGISTRY}


@pytest.mark.parametrize("scene", ["drop", "closeup", "map", "stack"])
def test_a_page_opens_on_the_scene_its_url_names(scene):
    """Only that scene is on screen, computed, and its tab chosen (the query is read before
    the scenes exist, and the tab follows the state)."""
    explorer = rendered({"scene": scene})
    assert list(explorer.scenes) == [scene]  # the others are not even built
    assert explorer.scenes[scene].active
    assert explorer.tabs.active == SCENES.index(scene)
    assert explorer.scenes[scene].computations == 1
    explorer.state.scene = "drop" if scene != "drop" else "map"
    assert not explorer.scenes[scene].active
    assert explorer.scenes[explorer.state.scene].active
    assert explorer.tabs.active == SCENES.index(explorer.state.scene)


@pytest.mark.parametrize("scene", ["drop", "closeup", "map", "stack"])
def test_a_scene_is_drawn_once_when_its_page_opens(scene, monkeypatch):
    """Its layout draws it; it is not redrawn on top for having come on screen (the Stack was
    drawn twice, its data sent again after the page's document). Back on screen after another
    scene, it is redrawn (once). (The Accuracy scene measures instead: test_app_accuracy.py.)"""
    redraws = []
    monkeypatch.setattr(Scene, "redraw_now", lambda self: redraws.append(type(self).__name__))
    explorer = rendered({"scene": scene})
    assert redraws == []
    assert explorer.scenes[scene].computations == 1  # (drawn, by its layout)
    explorer.state.scene = "drop" if scene != "drop" else "map"
    explorer.state.scene = scene
    assert redraws.count(type(explorer.scenes[scene]).__name__) == 1


@pytest.mark.parametrize("present", [False, True])
def test_every_scene_builds_a_valid_document(present):
    """Bokeh's check of a document's construction (a renderer without data, a layout without
    children, ...), which the served app skips for every session (app/app_hooks.py): done here,
    once, on a page with every scene built."""
    from bokeh.core.validation.check import check_integrity

    explorer = Explorer({"present": "1"} if present else {})
    for name in SCENES:
        explorer.scene(name)
    document = Document()
    explorer.page().server_doc(document)
    issues = check_integrity(list(document.models))
    assert len(document.models) > 300  # (every scene is in it)
    assert issues.error == []
    # empty layouts are allowed: those filled when first used (the folded "advanced" card, the
    # lesson's steps before it starts) cost a page nothing until then
    assert {issue.name for issue in issues.warning} <= {"EMPTY_LAYOUT"}


def test_a_page_carries_no_root_that_nothing_uses():
    """The page's roots: the sidebar, the main area and the location, not Panel's script area,
    modal actions or browser report (app/static/classroom.html); its HTML embeds each root
    it has (a root without a place in the page fails in the browser)."""
    from bokeh.embed.elements import html_page_for_render_items
    from bokeh.embed.util import RenderItem, standalone_docs_json_and_render_items

    document = Document()
    pn.config.browser_info = True  # (main.py turns it off; the template must not need it)
    try:
        Explorer({}).page().server_doc(document)
    finally:
        pn.config.browser_info = False
    names = sorted(root.name.split("-")[0] for root in document.roots)
    assert names == ["location", "main", "nav"]
    docs_json, _ = standalone_docs_json_and_render_items(document.roots)
    item = RenderItem(docid=next(iter(docs_json)), roots=document.roots)
    html = html_page_for_render_items(
        ({}, {}),
        docs_json,
        [item],
        "page",
        template=document.template,
        template_variables=document.template_variables,
    )
    for root in document.roots:
        assert f'data-root-id="{root.id}"' in html


def test_a_page_asks_its_style_sheets_of_the_server_only():
    """Every style sheet a page imports (the design's, the components' own), on the page opened
    and on a scene built when first visited, is asked of where the server serves Panel's files
    (the document's dist_url, as app/main.py sets it), never of Panel's CDN: the app must not
    reach the network. (A page built for a served session is held by the wheel's browser test,
    test_app_serve.py, which caught the design's pass pointing them at the CDN there: a fault
    this document without a session does not show.)"""
    from bokeh.models import ImportedStyleSheet
    from panel.io.state import set_curdoc

    document = Document()
    document.template_variables["dist_url"] = "served/"
    with set_curdoc(document):
        explorer = Explorer({"scene": "drop"})
        with document.models.freeze():  # (as app/main.py)
            explorer.page().server_doc(document)
        explorer.state.scene = "stack"  # (built now: the design's hooks style it)
    urls = {m.url for m in document.models if isinstance(m, ImportedStyleSheet)}
    assert any(url.startswith("served/") for url in urls)
    assert all(not url.startswith("http") for url in urls), sorted(urls)
    stack = {
        sheet.url
        for component in explorer.scenes["stack"].__panel__().select(pn.viewable.Viewable)
        for model, _ in component._models.values()
        for sheet in getattr(model, "stylesheets", [])
        if isinstance(sheet, ImportedStyleSheet)
    }
    assert stack and stack <= urls


def test_the_stack_scene_computes_only_for_its_own_parameters():
    explorer = rendered()
    explorer.state.scene = "stack"
    assert explorer.scenes["stack"].computations == 1
    drops = explorer.scenes["drop"].computations
    explorer.state.balls = 4
    assert explorer.scenes["stack"].computations == 2
    explorer.state.mu = 0.03  # a two-ball parameter: the stack does not recompute
    assert explorer.scenes["stack"].computations == 2
    assert explorer.scenes["drop"].computations == drops  # off screen: stale, not recomputed
    assert "4 balls, linear force" in explorer.scenes["stack"].summary.object


def _models_by_scene(explorer: Explorer):
    """The explorer in a document, and the scene whose tab holds each Bokeh model."""
    from bokeh.models import Tabs

    for name in SCENES:  # every scene built and rendered, as after a tour of the tabs
        explorer.scene(name)
    document = Document()
    root = explorer.__panel__().get_root(document)
    document.add_root(root)
    tabs = next(model for model in root.references() if isinstance(model, Tabs))
    owners = {
        model.id: name
        for name, panel in zip(SCENE_REGISTRY, tabs.tabs, strict=True)
        for model in panel.child.references()
    }
    return document, owners


def _changed(explorer: Explorer, document: Document, owners: dict, change) -> dict[str, int]:
    """How many Bokeh models of each scene's tab a change of the state modifies."""
    events = []
    document.on_change(events.append)
    change()
    document.remove_on_change(events.append)
    counts = dict.fromkeys(SCENE_REGISTRY, 0)
    for model in {getattr(event, "model", None) for event in events}:
        if model is not None and model.id in owners:
            counts[owners[model.id]] += 1
    return counts


def test_a_move_redraws_only_the_scene_on_screen():
    """A class moving sliders at once costs the server what one move redraws: a scene off
    screen must not redraw (the map's star once followed mu itself, ~100 ms a move)."""
    explorer = Explorer({})
    document, owners = _models_by_scene(explorer)
    counts = _changed(explorer, document, owners, lambda: explorer.state.param.update(mu=0.03))
    assert counts["drop"] > 0
    assert {name: n for name, n in counts.items() if name != "drop"} == dict.fromkeys(
        ("closeup", "map", "accuracy", "stack"), 0
    )
    explorer.state.scene = "map"
    moves = _changed(explorer, document, owners, lambda: explorer.state.param.update(mu=0.05))
    assert moves["map"] > 0 and moves["drop"] == 0


def test_only_the_scene_on_screen_computes():
    explorer = rendered()
    assert computations(explorer) == {"drop": 1, "closeup": 0, "map": 0, "accuracy": 0, "stack": 0}
    explorer.state.mu = 0.02
    assert computations(explorer) == {"drop": 2, "closeup": 0, "map": 0, "accuracy": 0, "stack": 0}
    explorer.tabs.active = 1  # the first-collision tab
    assert explorer.state.scene == "closeup"
    assert computations(explorer) == {"drop": 2, "closeup": 1, "map": 0, "accuracy": 0, "stack": 0}
    explorer.state.eps = 0.7
    explorer.state.tau_ratio = 0.2
    assert computations(explorer) == {"drop": 2, "closeup": 3, "map": 0, "accuracy": 0, "stack": 0}
    explorer.tabs.active = 0  # back to the drop: recomputed once, for the latest state
    assert computations(explorer) == {"drop": 3, "closeup": 3, "map": 0, "accuracy": 0, "stack": 0}
    assert explorer.scenes["drop"].result.drop.eps == 0.7


def test_drop_scene_plots_the_check_values_of_model_md():
    scene = rendered(PAPER).scenes["drop"]
    apexes = scene.apexes.data["h"]
    assert apexes[0] == pytest.approx(9256.04845, rel=1e-9)
    assert apexes[1] == pytest.approx(50076.3922, rel=1e-9)
    assert scene.result.contacts_first[BALLS] == 4
    # the curve reaches the apexes and runs to the second one only
    assert np.max(scene.curves.data["x2"]) == pytest.approx(50076.3922, rel=1e-6)
    assert scene.curves.data["t"][-1] == np.float32(scene.result.t2)  # (sent as float32)
    assert scene.icm_line.location == pytest.approx(scene.result.h_icm)
    assert "delayed rebound" in scene.summary.object


def test_si_units_scale_heights_and_times():
    explorer = rendered(PAPER)
    scene = explorer.scenes["drop"]
    t, x2 = scene.plotted.t, scene.plotted.x2  # the exact drop at the plotted times
    assert np.array_equal(scene.curves.data["x2"], x2.astype(np.float32))
    explorer.controls.units.value = "SI"
    assert explorer.state.units == "SI"
    # (the browser gets float32: equal to the scaled values rounded to float32)
    assert np.array_equal(scene.curves.data["t"], (t * presets.time_scale()).astype(np.float32))
    assert np.array_equal(scene.curves.data["x2"], (x2 * presets.length_scale()).astype(np.float32))
    assert scene.heights.yaxis.axis_label == "height [m]"
    top = max(scene.result.apex_h + [scene.result.h_icm]) * presets.length_scale()
    assert top < scene.heights.y_range.end < 1.2 * top  # the axis follows the units
    # the drop height input now speaks metres: 1 m typed is H = 1 m k / (m1 g)
    explorer.controls.height.value = "1"
    assert explorer.state.height == pytest.approx(presets.height_from_metres(1.0))


def test_the_drop_height_reads_round_metres_and_its_meaning_speaks_metres():
    """In metres the default H read 0.994898 m and its meaning spoke of a dimensionless
    height: three digits, a meaning in metres, and a typed height kept as typed."""
    explorer = rendered({"units": "SI"})
    controls = explorer.controls
    assert controls.height.value == "0.995" and explorer.state.height == 1e4
    assert "**drop height [m]**: in metres" in controls.meanings.object
    assert "**H**" not in controls.meanings.object
    controls.height.value = "1.2345"  # (more digits than shown: kept, and used)
    assert controls.height.value == "1.2345"
    assert explorer.state.height == pytest.approx(presets.height_from_metres(1.2345))
    controls.units.value = "dimensionless"
    assert controls.height.value == f"{presets.height_from_metres(1.2345):.6g}"
    assert "**H**: the drop height in units of" in controls.meanings.object


def test_closeup_shows_the_four_contacts_and_forces_only_inside_them():
    explorer = rendered({**PAPER, "scene": "closeup"})
    scene = explorer.scenes["closeup"]
    result = scene.result
    assert result.contacts_first[BALLS] == 4 and "**4 ball contacts**" in scene.table.object
    ball = [c for c in result.contacts if c.contact == BALLS]
    floor = [c for c in result.contacts if c.contact == FLOOR]
    tr = result.trajectory
    # the window holds the whole collision and stops long before the first apex
    assert tr.t[0] < min(c.start for c in result.contacts)
    assert tr.t[-1] > max(c.end for c in result.contacts)
    assert tr.t[-1] - tr.t[0] < 0.1 * result.t1
    # forces (sampled from the phases) push exactly inside the contact intervals (found by the
    # run's root finding): a consistency check between two parts of the solver
    inside_ball = np.zeros(tr.t.shape, bool)
    for c in ball:
        inside_ball |= (tr.t > c.start + 1e-9) & (tr.t < c.end - 1e-9)
    edges = np.zeros(tr.t.shape, bool)
    for c in ball:
        edges |= np.isclose(tr.t, c.start, atol=1e-9) | np.isclose(tr.t, c.end, atol=1e-9)
    assert np.all(tr.f12[inside_ball] > 0)
    assert np.all(tr.f12[~inside_ball & ~edges] == 0)
    # all four ball contacts happen while the lower ball is on the floor (model.md)
    assert all(floor[0].start < c.start and c.end < floor[0].end for c in ball)


def test_closeup_s_caption_says_why_the_floor_force_jumps():
    """The floor force jumps at a contact's start (the dashpot's force, proportional to the
    speed at first touch: docs/model.md), which a teacher took for a fault: the caption above
    the plots says why."""
    explorer = rendered({**PAPER, "scene": "closeup"})
    scene = explorer.scenes["closeup"]
    tr = scene.result.trajectory
    floor = min((c for c in scene.result.contacts if c.contact == FLOOR), key=lambda c: c.start)
    first = np.argmax(tr.t > floor.start + 1e-9)  # the first sample inside the contact
    assert tr.f01[first] > 0.04 * tr.f01.max()  # a jump, not a rise from 0
    holder = explorer._holders["closeup"]
    (caption,) = [o for o in holder.objects if isinstance(o, pn.pane.Markdown)]
    assert (
        "The floor force starts with a jump, not from 0: in this spring-and-dashpot model the "
        "damping pushes in proportion to the speed" in caption.object
    )


def test_closeup_s_table_names_its_time_unit():
    """The contacts' table had no unit: in SI its times are seconds, said in its heads, and
    are the solver's dimensionless times scaled by the preset's time scale."""
    from twoball import presets

    explorer = rendered({**PAPER, "scene": "closeup", "units": "SI"})
    text = explorer.scenes["closeup"].table.object
    assert "| contact | starts [s] | ends [s] | lasts [s] |" in text
    s = explorer.state
    solved = twoball.simulate(s.eps, s.mu, s.tau_ratio, height=s.height, until="first")
    first = min(solved.contacts, key=lambda c: c.start)
    name = "ball" if first.contact == BALLS else "floor"
    (row,) = [line for line in text.splitlines() if line.startswith(f"| {name} 1 |")]
    assert float(row.split("|")[2]) == pytest.approx(first.start * presets.time_scale(), 1e-5)
    explorer.state.units = "dimensionless"
    assert "| contact | starts (tau) | ends (tau) | lasts (tau) |" in (
        explorer.scenes["closeup"].table.object
    )


@pytest.mark.parametrize("query", [PAPER, {"mu": "0.5", "tau_ratio": "10"}])
def test_closeup_s_projected_table_has_a_contact_a_column(query):
    """On a projector the contacts' table is turned, a contact a column under one line (as
    rows it ran below a 1280 x 720 screen): its heads name every contact before the first
    apex, its rows give their start, end and duration, as the solver finds them."""
    explorer = rendered({**query, "scene": "closeup", "present": "1"})
    lines = explorer.scenes["closeup"].table.object.splitlines()
    s = explorer.state
    solved = twoball.simulate(s.eps, s.mu, s.tau_ratio, height=s.height, until="first")
    assert lines[0].endswith("before the first apex:") and len(lines) == 7, lines
    rows = {line.split("|")[1].strip(): line.split("|")[2:-1] for line in lines[2:]}
    names = [name.strip() for name in rows["contact"]]
    starts, ends = rows["starts (tau)"], rows["ends (tau)"]
    found = {}
    for name, start, end in zip(names, starts, ends, strict=True):
        if re.fullmatch(r"(ball|floor) \d+", name):
            found[name] = (float(start), float(end))
    for kind, label in ((BALLS, "ball"), (FLOOR, "floor")):
        exact = sorted((c.start, c.end) for c in solved.contacts if c.contact == kind)
        listed = [found[f"{label} {i}"] for i in range(1, len(exact) + 1)]
        assert np.ravel(listed) == pytest.approx(np.ravel(exact), rel=1e-5)
    assert len(found) == len(solved.contacts)


@pytest.mark.parametrize(
    "query",
    [
        {"eps": "1", "mu": "10", "tau_ratio": "10", "H": "1e8"},  # a new user's: 5 and 5
        {"eps": "0.3", "mu": "0.01", "tau_ratio": "1"},  # a second floor bounce before h1
        PAPER,  # all in one collision
        {"mu": "0.5", "tau_ratio": "10"},  # the floor bounce alone, then the balls meet
    ],
)
def test_closeup_s_table_lists_every_contact_its_summary_counts(query):
    """The summary counts the contacts before the first apex; the table had listed only the
    first collision's (at a large gap, the lower ball's floor bounce alone: '5 ball contacts'
    over a table of 'floor 1'). Each contact the solver finds is a row, and the summary says
    which rows the plots show."""
    explorer = rendered({**query, "scene": "closeup"})
    text = explorer.scenes["closeup"].table.object
    s = explorer.state
    solved = twoball.simulate(s.eps, s.mu, s.tau_ratio, height=s.height, until="first")
    floors, balls = solved.contacts_first
    rows = [line for line in text.splitlines() if re.match(r"\| (ball|floor) \d", line)]
    for kind, count, name in ((BALLS, balls, "ball"), (FLOOR, floors, "floor")):
        assert f"{count} {name} contact" in text.splitlines()[0]
        starts = [float(r.split("|")[2]) for r in rows if r.startswith(f"| {name} ")]
        exact = sorted(c.start for c in solved.contacts if c.contact == kind)
        assert len(starts) == count == len(exact)
        assert starts == pytest.approx(exact, rel=1e-5)
    grouped = collisions(solved.contacts)
    # the plots show the collisions up to the first in which the balls touch
    touch = next(i for i, g in enumerate(grouped) if any(c.contact == BALLS for c in g))
    shown = sum(len(g) for g in grouped[: touch + 1])
    if shown < len(solved.contacts):  # the plots' window said, and where the table leaves it
        what = "the first collision alone" if touch == 0 else "the collisions up to the balls'"
        assert f"The plots show {what}" in text
        assert f"the table lists {len(solved.contacts) - shown} more" in text
        assert "after the collision shown" in text
    else:
        assert "after the collision" not in text
        assert ("all in the first collision" if touch == 0 else "all up to the balls'") in text
    # the balls' first contact is in the plots' window, and their force pushes there
    tr = explorer.scenes["closeup"].result.trajectory
    contact = min((c for c in solved.contacts if c.contact == BALLS), key=lambda c: c.start)
    assert tr.t[0] < contact.start and contact.end < tr.t[-1]
    assert tr.f12.max() > 0


def test_accuracy_computes_only_when_opened():
    explorer = rendered({"eps": "0.816", "mu": "0.05", "tau_ratio": "0.3"})
    explorer.state.mu = 0.06
    assert "accuracy" not in explorer.scenes  # not even built until opened
    explorer.state.scene = "accuracy"
    scene = explorer.scenes["accuracy"]
    assert scene.computations == 1
    exact = [r for r in scene.rows if r.method == "exact"]
    assert exact and exact[0].rel_err_h1 == 0.0
    lsoda = {r.tolerance: r for r in scene.rows if r.method == "LSODA"}
    # tighter tolerance, smaller error against the exact solver
    assert lsoda[1e-9].rel_err_h1 < lsoda[1e-3].rel_err_h1
    assert "LSODA" in scene.table.object
    assert scene.view.loading is False and scene.status.object == ""  # done: nothing pending


def test_a_class_at_one_drop_measures_the_accuracy_once(monkeypatch):
    """Every page at the same drop shows the same rows, measured once per server; another drop
    is measured anew."""
    import app.accuracy
    from twoball.studies import precision

    calls = []

    def counted(*args, **kwargs):
        calls.append(args)
        return precision.work_precision(*args, **kwargs)

    monkeypatch.setattr(app.accuracy, "work_precision", counted)
    app.accuracy.measured.cache_clear()
    query = {"scene": "accuracy", "eps": "0.7", "mu": "0.2", "tau_ratio": "0.5"}
    pages = [rendered(query) for _ in range(3)]
    assert len(calls) == 1
    assert pages[0].scenes["accuracy"].rows == pages[2].scenes["accuracy"].rows
    pages[1].state.mu = 0.3
    assert len(calls) == 2 and calls[-1][1] == 0.3
    app.accuracy.measured.cache_clear()


def test_accuracy_measured_while_compiling_is_measured_again_once_compiled(monkeypatch):
    """Run times taken on the kernels' Python stand-ins (a first start) are not shown for the
    rest of the server's life: once the two-ball solver's kernels are compiled (the stacks'
    may still be compiling) the drop is measured again."""
    import app.accuracy
    from twoball import jit

    calls = []
    monkeypatch.setattr(app.accuracy, "work_precision", lambda *a, **k: calls.append(a) or [])
    app.accuracy.measured.cache_clear()
    query = {"scene": "accuracy", "eps": "0.7", "mu": "0.2", "tau_ratio": "0.5"}
    # (the two-ball solver's kernels on their stand-ins; the stacks' do not matter here)
    monkeypatch.setattr(jit, "python_modules", set(jit.KERNEL_MODULES))
    rendered(query)
    rendered(query)
    assert len(calls) == 1
    monkeypatch.setattr(jit, "python_modules", {"twoball.kernels.stack"})
    page = rendered(query)
    assert len(calls) == 2
    page.state.scene = "drop"  # away and back: nothing new to measure
    page.state.scene = "accuracy"
    assert len(calls) == 2
    app.accuracy.measured.cache_clear()


def test_the_accuracy_of_the_last_drop_is_dimmed_while_the_next_is_measured(monkeypatch):
    """While a new drop is measured (seconds, in a thread under a server) the plot and table
    of the drop before stay on screen dimmed, not at full strength as if current."""
    import app.accuracy

    explorer = rendered({"scene": "accuracy", "eps": "0.7", "mu": "0.2", "tau_ratio": "0.5"})
    scene = explorer.scenes["accuracy"]
    shown_while_measuring = []
    measure = scene._work

    def watched():
        shown_while_measuring.append((dict(scene.results.styles), scene.status.object))
        return measure()

    monkeypatch.setattr(scene, "_work", watched)
    explorer.state.mu = 0.3
    ((styles, status),) = shown_while_measuring
    assert styles == app.accuracy.STALE and "Computing" in status
    assert scene.results.styles == {"opacity": "1"} and scene.status.object == ""


@pytest.mark.parametrize("units", ["dimensionless", "SI"])
def test_typed_values_follow_one_rule_clamp_a_number_keep_the_last_for_text(units):
    """Under "advanced", one rule (app/state.typed_value): a number out of range is clamped to
    the nearest allowed value, text that is no number keeps the value in use, each with a
    message under the inputs. (A typed H of 1e20 was clamped but 0 fell back to the default;
    an eps12 of 2 fell back instead of being clamped.)"""
    explorer = rendered({"units": units})
    controls, state = explorer.controls, explorer.state
    lowest, highest = ExplorerState.param.height.bounds
    si = units == "SI"
    # (what the box takes, as its messages write it: metres rounded, app/state.metres_text)
    shown = (lambda h: metres_text(presets.metres_from_height(h))) if si else number_text
    message = controls.typed_message
    for typed, expected in (("0", lowest), ("-5", lowest), ("1e20", highest), ("inf", highest)):
        state.height = 2e4
        controls.height.value = typed
        assert state.height == pytest.approx(expected, rel=1e-12), typed
        assert explorer.scenes["drop"].result.drop.height == state.height
        assert message.visible and "outside the explorer's range" in message.object, typed
        assert f"using the nearest, {shown(expected)}" in message.object
    state.height = 2e4
    controls.height.value = "abc"
    assert state.height == 2e4  # kept
    assert message.visible and "got 'abc'" in message.object and "Keeping" in message.object
    low, high = ExplorerState.param.eps12.bounds
    for typed, expected in (("2", high), ("0", low), ("-1", low)):
        state.eps12 = 0.5
        controls.eps12.value = typed
        assert state.eps12 == expected, typed
        assert "eps12" in message.object and "using the nearest" in message.object
    state.eps12 = 0.5
    controls.eps12.value = "half"
    assert state.eps12 == 0.5 and "Keeping 0.5" in message.object
    controls.eps12.value = ""
    assert state.eps12 is None  # empty: equal to eps
    controls.eps12.value = "0.7"
    assert state.eps12 == 0.7 and not message.visible
    assert explorer.scenes["drop"].result.drop.eps12 == 0.7


@pytest.mark.parametrize("typed", ["0.0001", "1e9"])
def test_a_drop_height_typed_in_metres_outside_the_range_is_clamped_and_used(typed):
    """In metres, a height below (or above) the explorer's range is clamped to its end, and the
    drop uses it (below, the clamped metres came back as H = 9.999999999999998, which the state
    refused with a traceback, leaving the drop unchanged under a message that said otherwise)."""
    from app.state import app_range

    explorer = rendered({"units": "SI"})
    lowest, highest = app_range("height")
    explorer.controls.height.value = typed
    expected = lowest if float(typed) < 1 else highest
    assert explorer.state.height == expected
    assert explorer.scenes["drop"].result.drop.height == expected
    message = explorer.controls.typed_message
    assert message.visible and "outside the explorer's range" in message.object


@pytest.mark.parametrize("units", ["SI", "dimensionless"])
def test_a_clamped_height_shown_in_the_box_is_taken_back_without_a_message(units):
    """A height clamped to an end of the range shows in the box as a number that, typed back,
    lies within the range: the highest drop in metres showed as 9.95e+03 (above 9,948.975 m),
    and typing it back was refused as outside the range."""
    from app.state import app_range

    explorer = rendered({"units": units})
    controls, state = explorer.controls, explorer.state
    message = controls.typed_message
    to_units = presets.metres_from_height if units == "SI" else float
    for typed, end in (("1e20", max(app_range("height"))), ("-5", min(app_range("height")))):
        controls.height.value = typed
        assert state.height == pytest.approx(end, rel=1e-12) and message.visible
        shown = controls.height.value
        low, high = (to_units(h) for h in app_range("height"))
        assert low <= float(shown) <= high, shown
        state.height = 2e4  # (another drop, then the shown number typed back)
        controls.height.value = shown
        assert not message.visible, (shown, message.object)
        assert state.height == pytest.approx(end, rel=1e-3), shown  # (three digits)


def test_a_preset_sets_the_parameters_and_the_sliders():
    explorer = rendered()
    explorer.controls.preset.value = "ping-pong"
    preset = presets.PRESETS["ping-pong"]
    assert explorer.state.mu == preset.mu and explorer.state.eps12 == preset.eps12
    assert explorer.controls.sliders["mu"].value == pytest.approx(math.log10(preset.mu))
    assert explorer.state.height == pytest.approx(presets.height_from_metres(1.0))
    assert "ITTF" in explorer.controls.preset_source.object
    assert explorer.scenes["drop"].result.drop.mu == preset.mu


def test_a_shared_link_shows_its_preset_until_a_slider_moves():
    """The preset chosen is in the link, and a page opened from it shows the preset and its
    sources; a slider moved there forgets it (in the page and in its link)."""
    chosen = rendered()
    chosen.controls.preset.value = "tennis"
    shared = rendered(url_query(chosen.state))
    assert shared.controls.preset.value == "tennis" and shared.state.units == "SI"
    assert "ITF" in shared.controls.preset_source.object
    assert shared.controls.message.visible is False
    with param.edit_constant(shared.controls.sliders["mu"]):
        shared.controls.sliders["mu"].value_throttled = -1.5  # (as a release sets it)
    assert shared.state.mu == 0.0316  # (10 ** -1.5 to the slider's 3 digits)
    assert shared.controls.preset.value == "" and shared.controls.preset_source.object == ""
    assert "preset" not in url_query(shared.state)


def test_choosing_contacts_reads_their_slice_and_matches_the_solver():
    explorer = rendered({"eps": "0.816", "scene": "map"})
    scene = explorer.scenes["map"]
    scene.variable = "contacts_first"
    counts = scene.slice["contacts_first"]
    for i, j in ((5, 30), (20, 10)):
        mu, tau = float(counts["mu"][i]), float(counts["tau_ratio"][j])
        direct = twoball.simulate(scene.slice_eps, mu, tau, height=map_cube().attrs["height"])
        assert int(counts[i, j]) == direct.contacts_first[BALLS]


def test_a_lesson_step_covers_its_scene_until_the_answer_is_revealed():
    """A class predicts before it sees: the scene (computed underneath) is shown on reveal, and
    covered again on the next step; without the lesson nothing is covered."""

    def asked(explorer: Explorer) -> bool:  # the step's question, in place of the scene
        return bool(explorer.stage.objects) and explorer.stage.objects[0].visible

    explorer = rendered({"step": "3"})
    assert asked(explorer) and not explorer.tabs.visible
    assert explorer.scenes["drop"].computations == 1  # ready underneath
    lesson = explorer.lesson
    lesson.choices.value = lesson.choices.options[1]
    lesson._reveal()
    assert not asked(explorer) and explorer.tabs.visible
    lesson._go(4)
    assert asked(explorer) and not explorer.tabs.visible
    lesson._go(0)
    assert not asked(explorer) and explorer.tabs.visible
    assert not asked(rendered())


def test_a_reveal_disables_itself_before_the_answer_shows():
    """The browser applies the server's changes in order: while the answer is on screen,
    Reveal must already be disabled, or a clicker's next press (keys.js: Reveal while it is
    enabled, else Next) reveals again instead of going on."""
    explorer = rendered({"step": "1", "present": "1"})
    lesson = explorer.lesson
    order = []
    lesson.reveal.param.watch(lambda e: order.append(("reveal disabled", e.new)), "disabled")
    lesson.answer.param.watch(lambda e: order.append(("answer shown", e.new)), "visible")
    lesson._reveal()
    assert order.index(("reveal disabled", True)) < order.index(("answer shown", True))


def test_the_end_of_the_lesson_gives_back_the_teachers_drop():
    """A teacher's own drop, scene and units before Start come back at the lesson's end (the
    last step's drop and scene stayed, a new user's set-up lost)."""
    explorer = rendered({"eps": "0.5", "mu": "0.2", "tau_ratio": "2", "scene": "closeup"})
    before = {name: getattr(explorer.state, name) for name in ("eps", "mu", "tau_ratio")}
    lesson = explorer.lesson
    lesson._begin()
    assert explorer.state.units == "SI" and explorer.state.eps != 0.5
    for step in range(2, 7):
        lesson._go(step)
    assert explorer.state.scene == "accuracy"
    lesson._go(0)
    after = {name: getattr(explorer.state, name) for name in before}
    assert after == before and explorer.state.scene == "closeup"
    assert explorer.state.units == "dimensionless" and explorer.state.step == 0
    # a lesson opened from its URL (?step=3) has nothing to give back: its end stays put
    shared = rendered({"step": "3"})
    shared.lesson._go(0)
    assert shared.state.step == 0 and shared.state.scene == "drop"


def test_a_stack_outside_the_solver_is_refused_with_a_message():
    """Six balls at the smallest mass ratio make the top ball 1e-10 of the bottom one: the
    scene says so instead of raising, draws nothing, and draws again for a valid ratio."""
    explorer = rendered({"scene": "stack", "N": "6", "ratio": "0.01"})
    scene = explorer.scenes["stack"]
    assert scene.result is None and "outside what the solver carries" in scene.summary.object
    assert len(scene.curves.data["t"]) == 0
    explorer.state.stack_ratio = 0.2
    assert scene.result is not None and "6 balls, linear force" in scene.summary.object
    assert len(scene.curves.data["t"]) > 0


def test_a_stack_refused_after_one_carried_keeps_that_one_dimmed():
    """Seven balls at 0.04, then eight (the top ball 1.6e-10 of the bottom one): the message
    names the stack still plotted, dimmed; back to seven, undimmed."""
    explorer = rendered({"scene": "stack", "N": "7", "ratio": "0.04"})
    scene = explorer.scenes["stack"]
    plotted = scene.curves.data
    explorer.state.balls = 8
    assert scene.refused is not None and scene.result.stack.balls == 7
    assert "the last stack it carried, 7 balls with mass ratio 0.04" in scene.summary.object
    # in the class's words, with a way out that the solver takes
    assert "each 0.04 of the one below, the top ball is 2e-10 of the bottom" in scene.summary.object
    assert "ratio of at least 0.06, or at most 7 balls" in scene.summary.object
    assert "mass_ratios" not in scene.summary.object
    simulate_stack([0.06] * 7, 0.9, 0.2)  # (accepted: eight balls at 0.06)
    with pytest.raises(ParameterError):
        simulate_stack([0.05] * 7, 0.9, 0.2)
    assert scene.curves.data is plotted and scene._plots[0].styles["opacity"] == "0.35"
    explorer.state.balls = 7
    assert scene.refused is None and "7 balls, linear force" in scene.summary.object
    assert scene._plots[0].styles["opacity"] == "1"


def test_accuracy_explains_a_drop_without_a_bounce():
    """eps = 0.01, mu = 1: the upper ball comes to rest (simulate says so), so there is no
    apex to compare the methods on; the scene says that instead of a table of NaN."""
    query = {"eps": "0.01", "mu": "1", "tau_ratio": "1", "scene": "accuracy"}
    assert twoball.simulate(0.01, 1.0, 1.0).h1 is None  # the premise, from the library
    table = rendered(query).scenes["accuracy"].table.object
    assert "no bounce to measure" in table and "nan" not in table


def test_a_pinned_drop_stays_under_the_next_one_in_the_units_on_screen():
    """Tennis pinned, then ping-pong: both drawn (the pinned one dashed) and both summarised,
    each as simulate gives it, in metres; unpinned, only the current drop is left."""
    explorer = rendered()
    explorer.controls.preset.value = "tennis"
    scene = explorer.scenes["drop"]
    scene.pin.clicks += 1
    explorer.controls.preset.value = "ping-pong"
    scene.current()
    scene._draw()
    metres = presets.length_scale()
    runs = {}
    for key in ("tennis", "ping-pong"):
        p = presets.PRESETS[key]
        height = presets.height_from_metres(1.0)
        runs[key] = twoball.simulate(p.eps, p.mu, p.tau_ratio, eps12=p.eps12, height=height)
    assert explorer.state.units == "SI"
    pinned, now = scene.pinned_curves.data, scene.curves.data
    assert np.max(pinned["x2"]) == pytest.approx(runs["tennis"].h2 * metres, rel=1e-6)
    assert np.max(now["x2"]) == pytest.approx(runs["ping-pong"].h2 * metres, rel=1e-6)
    text = scene.summary.object
    assert "tennis ball on a basketball" in text.lower()
    for key in ("tennis", "ping-pong"):
        assert explorer.scenes["drop"]._drop_text(runs[key]).split("  \n")[0] in text
    assert scene.heights.legend[0].items[-1].visible
    assert scene.heights.legend[0].items[-1].label.value == "pinned drop"
    scene.pin.clicks += 1
    assert len(scene.pinned_curves.data["t"]) == 0 and "Pinned" not in scene.summary.object
    assert not scene.heights.legend[0].items[-1].visible


def test_the_stack_scene_takes_eight_balls_and_eps_per_contact_under_advanced():
    """Eight balls as the library computes them; eps per contact typed under "advanced" is
    used, a bad entry shows a message and the slider's eps is used; the URL carries it."""
    from app.state import url_query

    explorer = rendered({"scene": "stack", "N": "8", "ratio": "0.3"})
    scene = explorer.scenes["stack"]
    expected = twoball.simulate_stack([0.3] * 7, 0.9, 0.2)
    assert scene.result.h1 == expected.h1 and "8 balls" in scene.summary.object
    assert not scene.advanced.opened and not scene.eps_message.visible
    eps = [0.9, 0.8, 0.7, 0.6, 0.5, 0.9, 0.8, 0.7]
    scene.eps_contacts.value = ",".join(map(str, eps))
    assert explorer.state.stack_eps_contacts == scene.eps_contacts.value
    expected = twoball.simulate_stack([0.3] * 7, eps, 0.2)
    assert scene.result.h1 == expected.h1 and "eps per contact 0.9, 0.8" in scene.summary.object
    assert url_query(explorer.state)["eps_contacts"] == scene.eps_contacts.value
    scene.eps_contacts.value = "0.9, 0.8"  # two values for eight balls
    assert scene.eps_message.visible and "give 8 values for 8 balls" in scene.eps_message.object
    assert scene.advanced.opened and scene.eps_message in scene.advanced.body  # (seen at once)
    assert scene.result.h1 == twoball.simulate_stack([0.3] * 7, 0.9, 0.2).h1  # the slider's
    assert "eps_contacts" not in url_query(explorer.state)  # a wrong entry is not shared
    scene.eps_contacts.value = ", ".join(["0.5"] * 8)  # all equal, not the slider's 0.9
    assert scene.result.h1 == twoball.simulate_stack([0.3] * 7, 0.5, 0.2).h1
    assert "eps per contact 0.5, 0.5" in scene.summary.object  # said, though all are equal
    scene.eps_contacts.value = ""
    assert not scene.eps_message.visible and "eps per contact" not in scene.summary.object
    explorer.state.units = "SI"  # switched in another scene: this one says it has no metres
    assert "the stacks have no metres" in scene.summary.object


def test_a_page_opened_on_a_lesson_step_shows_its_units_on_the_switch():
    """A lesson's URL opens in metres: the units switch says so (it once showed dimensionless
    over plots drawn in metres)."""
    explorer = rendered({"step": "3", "present": "1"})
    assert explorer.state.units == "SI" and explorer.controls.units.value == "SI"
    assert "m" in explorer.scenes["drop"].heights.yaxis[0].axis_label


def test_trails_are_drawn_under_the_balls_when_first_asked_for():
    """The trails' lines join the animation when first asked for (a page that never asks for
    them does not pay for them), under the balls, shown and hidden with the box; the browser
    draws them as it plays (app/animation.py), so its callback knows them."""
    explorer = rendered()
    scene = explorer.scenes["drop"]
    before = len(scene.animation.renderers)
    scene.trails.value = [TRAILS]
    renderers = scene.animation.renderers
    assert len(renderers) == before + 2
    assert [r.data_source for r in renderers[:2]] == [scene.trail, scene.trail]  # underneath
    assert scene.animated.on_frame.args["trail_lines"] == renderers[:2]
    assert all(line.visible for line in renderers[:2])
    # behind the balls (drawn first, where the balls are), not beside them
    assert {line.glyph.x for line in renderers[:2]} == set(scene.balls.data["x"]) == {0.0}
    scene.trails.value = []
    assert not any(line.visible for line in renderers[:2])
    scene.trails.value = [TRAILS]  # once added, never twice
    assert len(scene.animation.renderers) == before + 2


def test_trails_asked_for_while_paused_have_their_frames_at_once():
    """The trail is drawn from the frames: asking for it sends them without the player moving
    (a new user saw trails only once play resumed), and while it is shown a new drop's frames
    go at once too (else its last drop's trail stayed on screen)."""
    explorer = rendered()
    scene = explorer.scenes["drop"]
    assert len(scene.animated.frames.data["t"]) == 0  # (not sent: nobody played)
    scene.trails.value = [TRAILS]
    first = np.asarray(scene.animated.frames.data["y1"]).copy()
    assert first.size == scene.times.size
    explorer.state.eps = 0.8
    scene.current()
    second = np.asarray(scene.animated.frames.data["y1"])
    assert second.size == scene.times.size and not np.array_equal(second[: first.size], first)
    scene.trails.value = []
    explorer.state.eps = 0.7
    scene.current()
    assert len(scene.animated.frames.data["t"]) == 0  # hidden: back to sending when played


def move_player(player, frame: int) -> None:
    """The player moved to ``frame`` as a browser's first move does: its value and
    value_throttled (which Panel keeps constant on the server's side)."""
    with param.edit_constant(player):
        player.param.update(value=frame, value_throttled=frame)


def test_the_animation_s_frames_are_the_drop_at_their_times():
    """The frames the browser plays: each ball's drawn centre less its radius (the lower ball)
    is its height from the solver at the frame's time, the upper ball stands on the lower one,
    and the caption says slow motion exactly inside a collision."""
    from app.collisions import collisions

    explorer = rendered({"units": "SI"})
    scene = explorer.scenes["drop"]
    assert len(scene.animated.frames.data["t"]) == 0  # sent when the player first moves
    assert scene.animation.title.text == "t = 0 s"  # the player's first frame, drawn here
    move_player(scene.player, 1)
    frames = scene.animated.frames.data
    result = scene.result
    units = twoball.units.units_named("SI")
    times = scene.times  # (the frames carry them as float32, as shown)
    assert np.allclose(np.asarray(frames["t"]), times * units.time, rtol=1e-6)
    assert times.size == scene.player.end + 1 and times[-1] == pytest.approx(result.end_time)
    exact = result.evaluate(times)
    radius, upper_radius = scene.balls.data["r"]
    lower = np.asarray(frames["y0"]) - radius
    upper = np.asarray(frames["y1"]) - 2 * radius - upper_radius
    scale = max(result.apex_h) * units.length
    assert np.allclose(lower, exact.x1 * units.length, rtol=0, atol=1e-6 * scale)
    assert np.allclose(upper, exact.x2 * units.length, rtol=0, atol=1e-6 * scale)
    windows = [(g[0].start, max(c.end for c in g)) for g in collisions(result.contacts)]
    inside = [any(a <= t <= b for a, b in windows) for t in times]
    assert list(np.asarray(frames["slow"], dtype=bool)) == inside
    assert 0 < sum(inside) < len(inside)
    explorer.state.eps = 0.8  # a new drop: its frames wait for the player again
    scene.current()
    assert len(scene.animated.frames.data["t"]) == 0
    assert scene.balls.data["y"][0] == pytest.approx(
        scene.result.evaluate(scene.times[1:2]).x1[0] * units.length + scene.balls.data["r"][0],
        rel=1e-12,
    )  # frame 1, where the player is, drawn from the server


@pytest.mark.parametrize("mu", ["0.0001", "1", "10"])
@pytest.mark.parametrize("present", ["0", "1"])
def test_the_drop_animation_s_balls_stay_on_its_stage(mu, present):
    """Every frame's balls lie inside the stage's height, at every mass ratio: at mu = 10 the
    upper ball, drawn 2.2 times the lower one's radius, was cut at the stage's top (the room
    above the heights was made for two balls of the lower one's size)."""
    explorer = rendered({"mu": mu, "H": "1e4", "present": present})
    scene = explorer.scenes["drop"]
    move_player(scene.player, 1)
    frames = scene.animated.frames.data
    radius, upper_radius = scene.balls.data["r"]
    assert upper_radius / radius == pytest.approx(float(mu) ** (1 / 3))  # equal densities
    span = scene.animation.y_range
    lower, upper = np.asarray(frames["y0"]), np.asarray(frames["y1"])
    assert upper.max() + upper_radius <= span.end, (upper.max() + upper_radius, span.end)
    assert lower.min() - radius >= span.start


def test_the_stack_animation_s_frames_are_the_stack_at_their_times():
    """The Stack scene's frames: each ball's drawn centre, less its radius and the diameters of
    the balls below it, is its height from an independent run of the solver at the frame's
    time; four balls, then three (the frames and the drawn balls as many as the stack has)."""
    from app.collisions import collisions

    explorer = rendered({"scene": "stack", "N": "4", "ratio": "0.3"})
    scene = explorer.scenes["stack"]
    for balls in (4, 3):
        explorer.state.balls = balls
        scene.current()
        move_player(scene.player, balls)  # the frames are sent
        frames = scene.animated.frames.data
        times = np.asarray(frames["t"], dtype=float)
        assert times.size == scene.player.end + 1 and times[0] == 0.0
        assert times[-1] == pytest.approx(scene.result.end_time, rel=1e-6)
        assert sorted(c for c in frames if c.startswith("y")) == [f"y{b}" for b in range(balls)]
        exact = twoball.simulate_stack(
            [0.3] * (balls - 1), 0.9, 0.2, until=scene.result.end_time, t_eval=scene.times
        ).trajectory
        below = 0.0
        scale = max(h for apexes in scene.result.apexes for _, h in apexes)
        radii = scene.balls_drawn.data["r"]
        assert len(radii) == balls and len(scene.balls_drawn.data["color"]) == balls
        for ball, radius in enumerate(radii):
            height = np.asarray(frames[f"y{ball}"], dtype=float) - radius - below
            assert np.allclose(height, exact.x[:, ball], rtol=0, atol=1e-6 * scale)
            below += 2 * radius
        # slow motion said in the caption exactly inside a collision, as for two balls
        windows = [(g[0].start, max(c.end for c in g)) for g in collisions(scene.result.contacts)]
        inside = [any(a <= t <= b for a, b in windows) for t in scene.times]
        assert list(np.asarray(frames["slow"], dtype=bool)) == inside
        assert 0 < sum(inside) < len(inside)


@pytest.mark.parametrize(
    ("time", "caption"),
    [(0.0, "t = 0 tau"), (5.46799993515, "t = 5.468 tau"), (1307.2, "t = 1307 tau"),
     (12345.0, "t = 12350 tau"), (1234.5, "t = 1235 tau"), (0.00123449, "t = 0.001234 tau"),
     (2.5, "t = 2.5 tau")],
)  # fmt: skip
def test_a_frame_s_caption_has_four_digits_as_javascript_writes_them(time, caption):
    """time_caption writes what the browser's String(Number(t.toPrecision(4))) does: the
    expected strings are what Node prints for these times (ties round up there, to even in
    Python's own formats)."""
    from app.animation import time_caption

    assert time_caption(time, "tau") == caption


def test_html_typed_as_eps_per_contact_is_shown_as_text():
    """A stack's eps per contact typed as HTML is quoted in its message, not rendered: no bold,
    no image loaded (a new user's <img src=x onerror=...> made the page request x)."""
    from html import unescape

    from bokeh.document import Document as BokehDocument

    explorer = rendered({"scene": "stack"})
    scene = explorer.scenes["stack"]
    explorer.state.stack_eps_contacts = "<b>x</b>, <img src=x onerror=alert(1)>"
    scene.current()
    assert scene.eps_message.visible
    html = unescape(scene.eps_message.get_root(BokehDocument()).text)  # (escaped to be sent)
    assert "<b>" not in html and "<img" not in html, html
    assert "&lt;b&gt;x" in html, html


def test_a_tall_stack_s_animation_plays_in_well_under_a_minute():
    """Eight balls: dozens of collisions share the slow-motion frames (each still at least ten
    frames inside it), so the animation lasts well under a minute at 25 frames a second (at 90
    frames a collision it had 5 368 frames, 3.5 minutes); a two-ball drop keeps 90 a collision."""
    from app.collisions import collisions
    from app.drop import COLLISION_FRAMES, FLIGHT_FRAMES, MIN_COLLISION_FRAMES, SLOW_FRAMES

    explorer = rendered({"scene": "stack", "N": "8", "ratio": "0.3"})
    scene = explorer.scenes["stack"]
    groups = [g for g in collisions(scene.result.contacts) if g[0].start < scene.result.end_time]
    assert len(groups) * COLLISION_FRAMES > SLOW_FRAMES  # (the case this is about)
    assert scene.times.size <= FLIGHT_FRAMES + max(SLOW_FRAMES, MIN_COLLISION_FRAMES * len(groups))
    assert scene.times.size / 25 < 40
    for group in groups:
        start, stop = group[0].start, max(c.end for c in group)
        inside = np.count_nonzero((scene.times >= start) & (scene.times <= stop))
        assert inside >= MIN_COLLISION_FRAMES
    drop = rendered({}).scenes["drop"]
    for group in collisions(drop.result.contacts):
        start, stop = group[0].start, max(c.end for c in group)
        assert np.count_nonzero((drop.times >= start) & (drop.times <= stop)) >= COLLISION_FRAMES


def test_the_sidebar_shows_the_sliders_of_the_scene_on_screen():
    """The Stack scene's own sliders replace the two-ball ones in the sidebar while it is on
    screen (two 'eps' sliders, one doing nothing there, confused a new user), and come back
    with any other scene."""
    explorer = rendered()
    controls = explorer.controls
    assert controls.two_ball.visible and controls.meanings.visible
    explorer.state.scene = "stack"
    own = explorer.scenes["stack"].own_controls()
    assert own in controls.scene_controls.objects and own.visible
    assert not controls.two_ball.visible and not controls.meanings.visible
    explorer.state.balls = 4  # the sliders there drive the stack
    assert "4 balls" in explorer.scenes["stack"].summary.object
    explorer.state.scene = "map"
    assert controls.two_ball.visible and controls.meanings.visible and not own.visible
    opened = rendered({"scene": "stack"})  # a page opened on the stack
    assert opened.controls.two_ball is None  # (made when a two-ball scene is first shown)
    assert opened.scenes["stack"].own_controls().visible


def test_an_apex_below_zero_is_explained_not_shown_as_a_missing_bounce():
    """At eps = 0.01, mu = 1e-4, tau_d/tau_f = 10 the upper ball's first apex is at X2 < 0: a
    real apex in free flight (its velocity 0, no ball force) while the lower ball is still
    pressed into the floor (X1 < 0, floor force on); the summary says so."""
    scene = rendered({"eps": "0.01", "mu": "0.0001", "tau_ratio": "10"}).scenes["drop"]
    drop = twoball.simulate(0.01, 1e-4, 10.0, dense_output=True)
    at_apex = drop.evaluate([drop.t1])
    assert drop.h1 < 0 and at_apex.f12[0] == 0 and abs(at_apex.v2[0]) < 1e-12
    assert at_apex.x1[0] < 0 and at_apex.f01[0] > 0  # the lower ball in the floor
    assert scene.result.h1 == drop.h1
    assert "below 0: the top ball barely left the ball under it" in scene.summary.object
    assert "below 0" not in rendered(PAPER).scenes["drop"].summary.object


def test_a_text_pane_sends_what_panels_markdown_pane_sends():
    """app.scene.Text sets only the model's text on a change: the same text Panel's Markdown
    pane (of the page's design) renders for the same object, and the same style sheets, which
    the text's model has from the start; its other properties still follow the pane."""
    import panel as pn

    from app.scene import PAGE_DESIGN, Text

    text, markdown = Text("**one**"), pn.pane.Markdown("**one**", design=PAGE_DESIGN)
    models = [pane.get_root(Document()) for pane in (text, markdown)]

    def sheets(model) -> list[str]:
        return [getattr(sheet, "url", sheet) for sheet in model.stylesheets]

    assert any(url.endswith("bootstrap.min.css") for url in sheets(models[0]))
    for new in ("**two** and *three*", "| a | b |\n| --- | --- |\n| 1 | 2 |", ""):
        assert sheets(models[0]) == sheets(models[1])
        text.object = markdown.object = new
        assert models[0].text == models[1].text
        assert sheets(models[0]) == sheets(models[1])
    assert "table" not in models[0].text  # (the last object, empty, was rendered too)
    text.object = "| a | b |\n| --- | --- |\n| 1 | 2 |"
    assert "&lt;table&gt;" in models[0].text  # (Panel sends the HTML escaped)
    text.styles = {"opacity": "0.5"}
    assert models[0].styles == {"opacity": "0.5"}


@pytest.mark.parametrize("scene", SCENES)
@pytest.mark.parametrize("present", ["0", "1"])
def test_a_page_s_text_panes_have_their_style_sheets_in_its_first_document(scene, present):
    """Each text pane (app.scene.Text) of a page, that of its URL's scene and that of a scene
    then opened from its tab, has in the page's document the style sheets Panel's full update
    would give it (its design's for a component of its own: Bootstrap's and the theme's), in
    that order. The template's pass gave it fewer (the text stood 20 px lower until a full
    update after the page had loaded brought them)."""
    from bokeh.models import ImportedStyleSheet
    from panel.io.state import set_curdoc

    from app.scene import PAGE_DESIGN, Text

    def named(sheets: list) -> list:
        return [sheet.url if isinstance(sheet, ImportedStyleSheet) else sheet for sheet in sheets]

    def checked(built) -> int:
        """Checks the text panes of a scene just put into the page: how many models."""
        count = 0
        for pane in {id(p): p for p in built.__panel__().select(Text)}.values():
            for model, _ in pane._models.values():
                sheets = named(model.stylesheets)
                assert any(str(url).endswith("/bootstrap.min.css") for url in sheets)
                assert sheets == named(pane._get_properties(document)["stylesheets"])
                count += 1
        return count

    document = Document()
    with set_curdoc(document):
        explorer = Explorer({"scene": scene, "present": present})
        page = explorer.page()
        assert page.design is PAGE_DESIGN  # (the text panes' own design is the page's)
        page.server_doc(document)
        assert checked(explorer.scenes[scene]) >= 1
        other = "stack" if scene != "stack" else "drop"
        explorer.state.scene = other  # (its tab chosen)
        assert checked(explorer.scenes[other]) >= 1


def test_the_accuracy_plot_draws_each_measured_method_from_its_rows():
    """One line and its points per method, from the rows measured (the exact solver's error
    at the floor), the legend naming the methods, every point inside the axes' ranges; each
    result a new figure, built whole."""
    from bokeh.models import GlyphRenderer, Legend, Line, Scatter

    explorer = rendered({"scene": "accuracy", "eps": "0.8", "mu": "0.05", "tau_ratio": "0.3"})
    scene = explorer.scenes["accuracy"]
    figures = []
    for drop in range(2):
        figure = scene.plot.object
        figures.append(figure)
        methods = list(dict.fromkeys(r.method for r in scene.rows))
        assert "exact" in methods and "LSODA" in methods
        expected = {
            method: [
                (r.seconds, r.shown_error)
                for r in scene.rows
                if r.method == method and math.isfinite(r.seconds)
            ]
            for method in methods
        }
        (legend,) = figure.select({"type": Legend})
        assert [item.label.value for item in legend.items] == methods
        for item, method in zip(legend.items, methods, strict=True):
            line, points = item.renderers
            assert isinstance(line.glyph, Line) and isinstance(points.glyph, Scatter)
            assert line.data_source is points.data_source
            data = line.data_source.data
            assert list(zip(data["seconds"], data["error"], strict=True)) == expected[method]
        assert len(figure.select({"type": GlyphRenderer})) == 2 * len(methods)
        shown = [p for points in expected.values() for p in points]
        assert all(figure.x_range.start < x < figure.x_range.end for x, _ in shown)
        assert all(figure.y_range.start < y < figure.y_range.end for _, y in shown)
        if drop == 0:
            explorer.state.mu = 0.1  # measured again: a new figure
    assert figures[0] is not figures[1]


def test_the_tennis_preset_says_why_it_is_no_textbook_bounce():
    """The tennis preset holds the balls touching: its first bounce is below the drop and its
    second higher (a delayed rebound), not the classic 3.7 times a teacher expects. Shown under
    the preset, with the solver's numbers and the gap that gives the textbook bounce."""
    explorer = rendered()
    explorer.controls.preset.value = "tennis"
    shown = explorer.controls.preset_source.object
    preset = presets.PRESETS["tennis"]
    height = presets.height_from_metres(presets.DEFAULT_DROP_METRES)

    def drop(tau_ratio):
        return twoball.simulate(preset.eps, preset.mu, tau_ratio, eps12=preset.eps12, height=height)

    touching, apart = drop(preset.tau_ratio), drop(1.0)
    assert touching.h1_over_drop < 1 and touching.delayed_rebound
    assert f"held touching (tau_d/tau_f = {preset.tau_ratio:g})" in shown
    assert f"{touching.h1_over_drop:.2f} times the drop height" in shown
    assert f"second bounce {touching.h2_over_h1:.1f} times higher" in shown
    assert not apart.delayed_rebound and round(apart.h1_over_drop, 1) == 3.7
    assert "a gap of tau_d/tau_f = 1 gives the textbook 3.7 times" in shown


@pytest.mark.parametrize("typed", ["0.0001", "1e9"])
def test_a_drop_height_in_metres_out_of_range_names_its_limits_rounded(typed):
    """In metres, the message states the range as a student reads it, "from about 0.99 mm to
    9.9 km" (it said "from 0.0009949 m to 9,949 m; using the nearest, 0.0009949 m"), while the
    height used is exactly the model's end of the range (H, not metres rounded)."""
    from app.state import app_range

    explorer = rendered({"units": "SI"})
    lowest, highest = app_range("height")
    low_m, high_m = presets.metres_from_height(lowest), presets.metres_from_height(highest)
    assert 1e-4 < low_m < 1e-2 and 1e3 < high_m < 1e4  # (an end in mm, one in km)
    explorer.controls.height.value = typed
    expected = lowest if float(typed) < 1 else highest
    assert explorer.state.height == expected  # exactly the model's end
    message = explorer.controls.typed_message.object
    assert f"from about {low_m * 1e3:.2g} mm to {high_m / 1e3:.2g} km" in message, message
    nearest = f"{low_m * 1e3:.2g} mm" if expected == lowest else f"{high_m / 1e3:.2g} km"
    assert f"using the nearest, about {nearest}." in message, message
    assert number_text(low_m) not in message and number_text(high_m) not in message


def test_a_stack_grown_to_eight_balls_has_its_model_graph_worked_out_once(monkeypatch):
    """Each line and legend entry added for a new ball had the document walk its whole model
    graph again (12 walks, 3 -> 8 balls, most of that move's 190 ms); the lines are added under
    one freeze. All eight lines are in the document and drawn from the stack's curves."""
    from bokeh.document.models import DocumentModelManager
    from panel.io.state import set_curdoc

    walks = []
    recompute = DocumentModelManager.recompute
    monkeypatch.setattr(
        DocumentModelManager, "recompute", lambda self: walks.append(1) or recompute(self)
    )
    document = Document()
    with set_curdoc(document):
        explorer = Explorer({"scene": "stack"})
        explorer.page().server_doc(document)
        scene = explorer.scenes["stack"]
        walks.clear()
        explorer.state.balls = 8
    assert len(walks) <= 2
    assert len(scene._lines) == 8
    assert all(line.document is document for line in scene._lines)
    assert [line.glyph.y for line in scene._lines] == [f"x{ball}" for ball in range(8)]
    assert all(f"x{ball}" in scene.curves.data for ball in range(8))


def test_a_reveal_shows_the_steps_own_drop_after_a_slider_moved_under_the_question():
    """The answer quotes the step's drop: a slider moved while the question covered the scene
    is moved back at the reveal, and the scene and the URL show the step's drop (a teacher's
    trial: "it rises to 8.8 m" over a plot of eps = 0.67, whose h1 was 3.1 m)."""
    from app.steps import STEPS

    explorer = rendered({"step": "1"})
    state, lesson = explorer.state, explorer.lesson
    state.eps = 0.67
    assert explorer.scenes["drop"].result.drop.eps == 0.67  # (computed underneath)
    lesson.choices.value = lesson.choices.options[STEPS[0].answer]
    lesson._reveal()
    drop = STEPS[0].drop
    assert {name: getattr(state, name) for name in drop} == drop
    expected = twoball.simulate(drop["eps"], drop["mu"], drop["tau_ratio"], height=drop["height"])
    assert explorer.scenes["drop"].result.h1 == expected.h1
    assert float(url_query(state)["eps"]) == drop["eps"]
    assert "Right." in lesson.answer.object


def test_the_lessons_buttons_run_their_scripts_without_panels_links():
    """The lesson's Start, Reveal, Previous and Next run their script in the browser from their
    Bokeh model's click (app/scene.ScriptedButton): each model carries it, and no component of
    the page is in Panel's registry of links (whose first entry makes Panel look through every
    model of every page it builds)."""
    from bokeh.models import CustomJS
    from panel.io.state import set_curdoc
    from panel.links import Callback
    from panel.reactive import Reactive

    from app.lesson import SHOW_ANSWER, SHOW_STEP

    document = Document()
    with set_curdoc(document):
        explorer = Explorer({"scene": "drop"})
        page = explorer.page()
        page.server_doc(document)
        explorer.lesson._begin()  # (the step's buttons are made at the first step)
    lesson = explorer.lesson
    scripts = {
        lesson.start: SHOW_STEP,
        lesson.reveal: SHOW_ANSWER,
        lesson.previous: SHOW_STEP,
        lesson.next: SHOW_STEP,
    }
    for button, script in scripts.items():
        models = list(button._models.values())
        assert models, button.label
        for model, _ in models:
            (click,) = model.js_event_callbacks["button_click"]
            assert isinstance(click, CustomJS) and click.code == script, button.label
    components = [c for item in page.roots().values() for c in item.select(Reactive)]
    assert len(components) > 20
    assert not [c for c in components if c in Callback.registry]


def test_a_page_makes_no_template_object_and_no_busy_spinner(monkeypatch):
    """app/explorer.ClassroomPage: after the process's first page, a page makes no Panel template
    (its lists, config, busy spinner and notebook view with its "Launch server" button: 12 ms
    of a page's opening); its document still gets the page's template and variables, without
    a busy area."""
    import panel as pn

    Explorer({}).page().server_doc(Document())  # (the process's shell: app.explorer.page_shell)
    made = []
    template_init = counted(pn.template.BaseTemplate.__init__, made, lambda params: "a template")
    button_init = counted(pn.widgets.Button.__init__, made, lambda params: params.get("label"))
    monkeypatch.setattr(pn.template.BaseTemplate, "__init__", template_init)
    monkeypatch.setattr(pn.widgets.Button, "__init__", button_init)
    document = Explorer({}).page().server_doc(Document())
    assert "a template" not in made and "Launch server" not in made
    assert document.template is page_shell(False, "", False).template
    assert document.template_variables["busy"] is False
    assert document.template_variables["nav"] is True
    pn.template.BootstrapTemplate()  # (Panel's own makes both: the count sees them)
    assert {"a template", "Launch server"} <= set(made)


def counted(own, made: list, name):
    """``own`` (an ``__init__``), noting each call in ``made`` as ``name(params)``."""

    def init(self, *args, **params):
        made.append(name(params))
        own(self, *args, **params)

    return init


def test_moves_made_while_the_accuracy_is_measured_are_measured_together_once(monkeypatch):
    """Under a server, one measurement at a time per page: four moves made while a drop is
    measured start no thread of their own; the newest drop alone is measured next, and only its
    rows are shown."""
    import asyncio
    import types

    from app.accuracy import AccuracyScene

    scene = AccuracyScene(state=ExplorerState())
    scene.active = True  # (computed at once, with no server)
    document = types.SimpleNamespace(session_context=object(), ticks=[])
    document.add_next_tick_callback = document.ticks.append
    started, measured, results = [], [], []

    def work():
        measured.append(scene.state.mu)
        if len(measured) == 1:  # four moves while the first drop is measured
            for mu in (0.02, 0.03, 0.04, 0.05):
                scene.state.mu = mu
        results.append([])  # (each measurement's rows, told apart by identity)
        return results[-1]

    monkeypatch.setattr(scene, "_work", work)
    monkeypatch.setattr("panel.state.execute", lambda callback: started.append(callback))
    monkeypatch.setattr("panel.state.curdoc", document, raising=False)
    scene.state.mu = 0.015
    assert len(started) == 1 and scene._measuring

    # the measurement run in this thread, the coroutine driven by hand (a test before may have
    # left this thread's event loop running, and the moves are made on the page's thread)
    async def here(function, *args):
        return function(*args)

    monkeypatch.setattr(asyncio, "to_thread", here)
    with pytest.raises(StopIteration):
        started[0]().send(None)
    assert len(started) == 1  # (the four moves started nothing)
    assert measured == [0.015, 0.05] and not scene._measuring
    (show,) = document.ticks
    show()
    assert scene.rows is results[-1] and scene.status.object == ""


def test_the_stack_s_summary_gives_h1_over_the_top_ball_s_release_height_written_out():
    """The Stack's ratio is h1 over the top ball's own release height (the stack's H plus the
    balls below it), which the summary names; a large one is written out ("1,330 times")."""
    from app.stack import times_text

    for balls in ("3", "8"):
        explorer = rendered({"scene": "stack", "N": balls})
        scene = explorer.scenes["stack"]
        r = scene.result
        release = r.stack.x_start[-1]
        text = scene.summary.object
        assert release > explorer.state.height
        assert f"{times_text(r.h1 / release)} times its release height" in text, text
        assert "e+" not in text.split("times its release height")[0], text
    assert [times_text(x) for x in (8.1834, 1334.9, 999.6, 0.5123)] == [
        "8.18",
        "1,330",
        "1,000",
        "0.512",
    ]


def test_a_url_s_scene_name_opens_its_scene_in_any_case():
    """?scene=Map opened the Drop, with a message: the Map's tab is shown, built, no message."""
    explorer = Explorer({"scene": "Map"})
    assert explorer.state.scene == "map"
    assert explorer.tabs.active == list(SCENE_REGISTRY).index("map")
    assert explorer.scenes["map"].active and "drop" not in explorer.scenes
    assert not explorer.controls.message.visible


TEXT_PAGES = [
    {"scene": "drop"},
    {"scene": "drop", "units": "SI", "present": "1"},
    {"scene": "drop", "eps": "0.3", "mu": "10"},
    {"scene": "closeup", "mu": "0.01"},
    {"scene": "map", "eps": "0.9"},
    {"scene": "accuracy"},
    {"scene": "stack", "N": "4", "force": "hertz", "units": "SI"},
    {"scene": "stack", "ratio": "0.02", "N": "8"},  # (refused: the solver's limit, said)
    {"scene": "stack", "stack_eps": "0.5, 0.7, 0.9", "N": "4"},
]


@pytest.mark.parametrize(
    "query", TEXT_PAGES, ids=lambda q: "&".join(f"{k}={v}" for k, v in q.items())
)
def test_every_text_renders_as_panels_markdown_pane(query):
    """app.scene.Text parses with CommonMark and tables (TEXT_MARKDOWN), not Panel's GFM-like
    parser: every text the scenes show (summaries, tables, notes, refusals, in both unit
    systems and on a projector) gives the same HTML as Panel's own Markdown pane."""
    from app.scene import Text

    explorer = Explorer(query)
    page = explorer.page()
    scene = explorer.scene(query["scene"])
    scene.active = True
    scene.redraw_now()
    shown = [page.main, page.sidebar, scene.__panel__()]
    texts = {id(pane): pane for area in shown for pane in area.select(Text) if pane.object}
    assert texts
    if query.get("ratio") == "0.02":
        assert any("outside what the solver carries" in pane.object for pane in texts.values())
    for pane in texts.values():
        markdown = pn.pane.Markdown(pane.object)
        assert pane._transform_object(pane.object) == markdown._transform_object(pane.object)


def _hue_and_saturation(colour: str) -> tuple[float, float]:
    """(hue in degrees, saturation) of a colour Bokeh names or writes in hex."""
    import colorsys

    from bokeh.colors import named

    hex_colour = getattr(named, colour).to_hex() if not colour.startswith("#") else colour
    red, green, blue = (int(hex_colour[i : i + 2], 16) / 255 for i in (1, 3, 5))
    hue, _, saturation = colorsys.rgb_to_hls(red, green, blue)
    return 360 * hue, saturation


def test_the_stack_s_balls_are_drawn_apart_from_the_chain_s_green():
    """A stack of three drew its top ball in Okabe-Ito's bluish green (hue 164 degrees) beside
    the chain's dotted green line (120 degrees), and a class took the one for the other (a
    teacher's trial): every ball's line, up to eight balls, is a grey, black or a colour at
    least 60 degrees of hue from the line's green, and no two balls share a colour."""
    explorer = Explorer({"scene": "stack", "N": "8"})
    scene = explorer.scenes["stack"]
    scene.__panel__().get_root(Document())
    colours = [line.glyph.line_color for line in scene._lines]
    assert len(colours) == 8 and len(set(colours)) == 8, colours
    icm_hue, _ = _hue_and_saturation(scene.icm_line.line_color)
    for colour in colours:
        hue, saturation = _hue_and_saturation(colour)
        apart = min(abs(hue - icm_hue), 360 - abs(hue - icm_hue))
        assert saturation < 0.05 or apart >= 60, (colour, hue, scene.icm_line.line_color)


@pytest.mark.parametrize("units", ["dimensionless", "SI"])
def test_the_first_collision_says_what_its_heights_are_measured_from(units):
    """The First collision's upper ball went to "height X" -135, which a teacher read as a
    height above the floor: each ball's coordinate is its own, 0 where it touches what is
    below it, and the axis and the scene's explanation say so."""
    explorer = Explorer({"scene": "closeup", "units": units})
    scene = explorer.scenes["closeup"]
    scene.__panel__().get_root(Document())
    label = scene.positions.yaxis[0].axis_label
    assert label.endswith(", from contact"), label
    assert label.startswith("height [m]" if units == "SI" else "height X"), label
    caption = SCENE_REGISTRY["closeup"].caption
    assert "Each ball's height is its own, from contact" in caption
    assert "X1 is 0 where the big ball just touches the floor" in caption
