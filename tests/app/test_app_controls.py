"""The sliders as a browser moves them: Bokeh applies the browser's changes to the slider's
model (``set_from_json``, as the server does with a PATCH-DOC), and Panel follows the release."""

from __future__ import annotations

import math

import pytest
from bokeh.document import Document
from panel.io.state import set_curdoc
from panel.reactive import Syncable

from app.explorer import Explorer
from app.state import url_query


@pytest.mark.parametrize(("scene", "name"), [("drop", "eps"), ("drop", "mu"), ("stack", "eps")])
def test_a_drag_costs_the_server_nothing_until_its_release(monkeypatch, scene, name):
    """A drag's ``value`` changes reach the slider's model only: Panel handles none of them
    (no event, no watcher, no drop computed); the release sets the slider's value and
    value_throttled, the state, and one new drop."""
    document = Document()
    with set_curdoc(document):
        explorer = Explorer({"scene": scene})
        explorer.page().server_doc(document)
    if scene == "stack":
        slider = next(w for w in explorer.scenes["stack"].widgets if w.name == name)
    else:
        slider = explorer.controls.sliders[name]
    model = next(m for m, _ in slider._models.values() if m.document is document)
    handled = []
    process = Syncable._process_events
    monkeypatch.setattr(
        Syncable,
        "_process_events",
        lambda self, events: handled.append(events) or process(self, events),
    )
    shown = explorer.scenes[scene]
    computed = shown.computations
    before = slider.value
    low, high = slider.start, slider.end
    steps = [low + (high - low) * f for f in (0.31, 0.42, 0.53, 0.64)]
    for value in steps:  # the drag
        model.set_from_json("value", value, setter="browser")
    assert model.value == steps[-1] and slider.value == before
    assert handled == [] and shown.computations == computed
    model.set_from_json("value_throttled", steps[-1], setter="browser")  # the release
    # (to 12 digits: the float's noise of a browser's step goes, ReleasedSlider)
    assert slider.value == slider.value_throttled == pytest.approx(steps[-1], rel=1e-12)
    assert [set(events) for events in handled] == [{"value_throttled"}]
    assert shown.computations == computed + 1


def test_the_advanced_inputs_are_made_and_shown_below_their_button_when_first_opened():
    """app/scene.Folded: a page's first document has the button alone (its inputs' models are
    in no page that never opens it); the first press makes the inputs and shows them right
    after the button, in the page's document; a second press hides them, a third shows the
    same inputs again."""
    document = Document()
    with set_curdoc(document):
        explorer = Explorer({})
        explorer.page().server_doc(document)
    controls = explorer.controls
    folded, layout = controls.advanced, controls.__panel__()
    height_models = lambda: [m for m, _ in controls.height._models.values()]  # noqa: E731
    assert folded.body is None and height_models() == []
    with set_curdoc(document):
        folded.button.value = True  # as the browser's press
    index = layout.objects.index(folded.button)
    assert layout.objects[index + 1] is folded.body and folded.body.visible
    assert list(folded.body) == [controls.typed_message, controls.height, controls.eps12]
    assert [m.document for m in height_models()] == [document]  # sent to the page
    body = folded.body
    folded.button.value = False
    assert not body.visible and folded.body is body
    folded.open()
    assert folded.opened and body.visible and layout.objects.count(body) == 1


def test_eps12_is_offered_only_where_it_drives_the_drop():
    """eps12 (the two-ball drop's ball-ball restitution) is hidden among the advanced inputs on
    the Stack scene, whose contacts have their own eps, and shown again on the others."""
    explorer = Explorer({"scene": "stack"})
    controls = explorer.controls
    controls.__panel__()  # (the advanced fold is made with the controls' layout)
    controls.advanced.open()
    assert controls.height.visible and not controls.eps12.visible
    explorer.tabs.active = list(explorer._holders).index("drop")
    assert explorer.state.scene == "drop" and controls.eps12.visible
    explorer.tabs.active = list(explorer._holders).index("stack")
    assert not controls.eps12.visible


def test_a_key_press_is_a_visible_step_and_a_link_keeps_its_digits():
    """One press of an arrow key moved eps by 0.001 and mu or tau_d/tau_f by 0.01 of a decade,
    a change no plot showed (a teacher's trial): each slider's step is a fiftieth to a
    hundredth of its range (a log slider's in log10). A linked value keeps its digits: the
    state and the slider hold ?eps=0.9137 and ?mu=0.0137, not the step's nearest."""
    explorer = Explorer({"eps": "0.9137", "mu": "0.0137"})
    sliders = explorer.controls.sliders
    for name, slider in sliders.items():
        assert 50 <= (slider.end - slider.start) / slider.step <= 100, name
    assert explorer.state.eps == 0.9137 and sliders["eps"].value == 0.9137
    assert explorer.state.mu == 0.0137
    assert math.isclose(sliders["mu"].value, math.log10(0.0137), rel_tol=1e-12)


def test_a_moved_slider_sets_a_short_value_and_an_old_link_keeps_its_digits():
    """A link shared after a drag carried mu=0.0446683592151 (ten to the log slider's -1.35),
    and a worksheet eps = 0.5700000000000001 (the browser's 0.01 + 56 * 0.01; a teacher's
    trial). A log slider released sets 3 significant digits, as its title shows, and eps the
    value without the float's noise; the handle stays where it was left. A link with long
    values still opens on them."""
    document = Document()
    with set_curdoc(document):
        explorer = Explorer({})
        explorer.page().server_doc(document)
    sliders = explorer.controls.sliders
    released = {"eps": 0.01 + 56 * 0.01, "mu": -4 + 53 * 0.05, "tau_ratio": -4 + 61 * 0.05}
    for name, position in released.items():
        slider = sliders[name]
        model = next(m for m, _ in slider._models.values() if m.document is document)
        model.set_from_json("value_throttled", position, setter="browser")
    state = explorer.state
    assert (state.eps, state.mu, state.tau_ratio) == (0.57, 0.0447, 0.112)
    assert url_query(state)["mu"] == "0.0447" and url_query(state)["tau_ratio"] == "0.112"
    assert sliders["mu"].value == pytest.approx(-1.35, abs=1e-12)  # (not log10(0.0447))
    old = Explorer({"eps": "0.5700000000000001", "mu": "0.0446683592151"})
    assert old.state.mu == 0.0446683592151 and url_query(old.state)["mu"] == "0.0446683592151"
    assert old.state.eps == 0.5700000000000001  # (accepted; the link's eps reads 0.57)
    assert old.controls.sliders["mu"].value == pytest.approx(math.log10(0.0446683592151))
