"""The explorer's state, URL reading, presets and units: plain Python, no browser."""

from __future__ import annotations

import math

import pytest

from app.state import (
    ExplorerState,
    app_range,
    preset_drop,
    read_query,
    typed_value,
    url_query,
    validate,
)
from twoball import presets
from twoball.model import Parameters


def test_validate_accepts_a_value_in_range():
    assert validate("mu", "0.02", 0.05) == (0.02, None)


@pytest.mark.parametrize(
    ("name", "text", "words"),
    [
        ("eps", "abc", "eps must be a number from 0.01 to 1; got 'abc'"),
        ("eps", "1.5", "eps must be a number from 0.01 to 1; got '1.5'"),
        ("mu", "-1", "mu must be a number from 0.0001 to 10"),  # (the explorer's range)
        ("height", "nan", "height must be a number from 10 to 100,000,000"),
        ("tau_ratio", "inf", "tau_ratio must be a number from 0.0001 to 10"),
    ],
)
def test_validate_falls_back_with_a_message_naming_the_parameter(name, text, words):
    fallback = getattr(Parameters, name)
    value, message = validate(name, text, fallback)
    assert value == fallback
    assert words in message and "Using" in message


def test_validate_clamps_valid_values_the_sliders_cannot_show():
    value, message = validate("mu", "100", 0.05)
    assert value == app_range("mu")[1]
    assert "outside the explorer's range" in message
    value, message = validate("tau_ratio", "0", 0.3)  # valid for the model, not on a log slider
    assert value == app_range("tau_ratio")[0] and message


@pytest.mark.parametrize("name", ["eps", "eps12", "mu", "tau_ratio", "height"])
def test_the_explorer_s_range_is_declared_once_and_inside_the_model_s(name):
    """Both ends of the explorer's range are valid drops and states; the sliders span it."""
    from app.controls import LOG_SLIDERS, Controls
    from twoball.model import check_value

    low, high = app_range(name)
    for edge in (low, high):
        assert check_value(name, edge) == edge  # the model accepts it
        assert validate(name, str(edge), None) == (edge, None)
        ExplorerState(**{name: edge})  # so does the state
    controls = Controls(state=ExplorerState())
    controls.show_scene_controls(None)  # (a two-ball scene's: its sliders made then)
    slider = controls.sliders.get(name)
    if slider is not None:
        ends = (math.log10(low), math.log10(high)) if name in LOG_SLIDERS else (low, high)
        assert (slider.start, slider.end) == pytest.approx(ends)


def test_empty_eps12_means_equal_to_eps():
    assert validate("eps12", "", 0.7) == (None, None)
    assert validate("eps12", "none", 0.7) == (None, None)


def test_read_query_keeps_good_values_and_reports_each_bad_one():
    defaults = ExplorerState()
    values, messages = read_query(
        {"eps": "0.7", "mu": "oops", "tau_ratio": "0.5", "H": "-3", "scene": "nowhere", "x": "1"},
        defaults,
    )
    assert values == {"eps": 0.7, "mu": defaults.mu, "tau_ratio": 0.5, "height": defaults.height}
    assert len(messages) == 3
    assert any(m.startswith("URL mu:") for m in messages)
    assert any(m.startswith("URL H:") for m in messages)
    assert any(m.startswith("URL scene:") for m in messages)


def test_a_link_s_height_limited_in_metres_is_said_in_metres():
    """A link's H beyond the range was limited to 1e8 with a message in H alone ("using
    100,000,000"): a page in metres, which shows the drop from 9.95e+03 m, never said it had
    been limited to about 9.9 km. It says so in metres too; a page in H and a lesson step's own
    drop do not."""
    values, messages = read_query({"H": "2e8", "units": "SI"}, ExplorerState())
    assert values["height"] == 1e8
    (message,) = messages
    assert message.startswith("URL H: height = 200,000,000 is outside the explorer's range")
    assert message.endswith("using 100,000,000. In metres: a drop from about 9.9 km."), message
    values, messages = read_query({"H": "abc", "units": "SI"}, ExplorerState())
    assert messages[0].endswith("In metres: a drop from about 0.99 m."), messages
    assert "metres" not in read_query({"H": "2e8"}, ExplorerState())[1][0]
    values, messages = read_query({"H": "2e8", "step": "1"}, ExplorerState())
    assert values["units"] == "SI" and "metres" not in messages[0]


@pytest.mark.parametrize(
    "text, scene", [("Map", "map"), ("STACK", "stack"), (" CloseUp ", "closeup")]
)
def test_read_query_takes_a_scene_s_name_in_any_case(text, scene):
    """?scene=Map (the tab's title reads "Delayed-rebound map", a teacher typed it capitalised)
    opened the Drop with a message: a scene's name is read in any case, and written back in
    its own (url_query)."""
    values, messages = read_query({"scene": text}, ExplorerState())
    assert messages == [] and values["scene"] == scene
    assert url_query(ExplorerState(scene=values["scene"]))["scene"] == scene


def test_url_query_round_trips_through_read_query():
    state = ExplorerState(eps=0.7321, mu=0.0123456, tau_ratio=0.456, height=2.5e4, eps12=0.6)
    state.scene = "map"
    values, messages = read_query(url_query(state), ExplorerState())
    assert messages == []
    for name in ("eps", "mu", "tau_ratio", "height", "eps12"):
        assert values[name] == pytest.approx(getattr(state, name), rel=1e-11)
    assert values["scene"] == "map"
    assert "eps12" not in url_query(ExplorerState())


def test_units_agree_with_free_fall_in_si():
    """Independent check of the scales: the lower ball falls h metres in sqrt(2 h / g) s, and in
    the model it reaches the floor at tau = sqrt(2 H)."""
    metres = 1.3
    height = presets.height_from_metres(metres)
    seconds = math.sqrt(2.0 * height) * presets.time_scale()
    assert seconds == pytest.approx(math.sqrt(2.0 * metres / presets.GRAVITY), rel=1e-12)
    assert presets.metres_from_height(height) == pytest.approx(metres, rel=1e-12)


def test_presets_follow_their_cited_drop_tests_and_masses():
    tennis, ping_pong = presets.PRESETS["tennis"], presets.PRESETS["ping-pong"]
    # FIBA: rebound 1200-1400 mm from 1800 mm; ITF: 53-58 in from 100 in; ITTF: 240-260 from 305
    assert math.sqrt(1200 / 1800) < tennis.eps < math.sqrt(1400 / 1800)
    assert math.sqrt(53 / 100) < tennis.eps12 < math.sqrt(58 / 100)
    assert math.sqrt(240 / 305) < ping_pong.eps12 < math.sqrt(260 / 305)
    # ITF 56.0-59.4 g, ITTF 2.7 g, FIBA 567-650 g
    assert 56.0 / 650 < tennis.mu < 59.4 / 567
    assert 2.7 / 650 < ping_pong.mu < 2.7 / 567
    for preset in (tennis, ping_pong):
        for name in ("eps", "eps12", "mu", "tau_ratio"):
            low, high = app_range(name)
            assert low <= getattr(preset, name) <= high
    # a 1 m drop of a basketball is of order H = 1e4 (model.md)
    assert 3e3 < presets.height_from_metres(1.0) < 3e4


def test_the_map_force_round_trips_and_a_bad_one_is_reported():
    state = ExplorerState(map_force="hertz")
    state.scene = "map"
    values, messages = read_query(url_query(state), ExplorerState())
    assert messages == [] and values["map_force"] == "hertz"
    values, messages = read_query({"map_force": "spring"}, ExplorerState())
    assert "map_force" not in values
    assert messages and messages[0].startswith("URL map_force: must be one of linear, hertz")


def test_the_stack_eps_per_contact_round_trips_and_bad_input_is_reported():
    state = ExplorerState(balls=8, stack_eps_contacts="0.9, 0.8,0.7,0.6,0.5,0.9,0.8,0.7")
    state.scene = "stack"
    query = url_query(state)
    assert query["N"] == "8" and query["eps_contacts"] == state.stack_eps_contacts
    values, messages = read_query(query, ExplorerState())
    assert messages == [] and values["balls"] == 8
    assert values["stack_eps_contacts"] == state.stack_eps_contacts
    assert "eps_contacts" not in url_query(ExplorerState(scene="stack"))  # empty: the slider's
    for text in ("0.9,oops", "0.9,1.5", "nan", ",".join(["0.9"] * 9)):
        values, messages = read_query({"scene": "stack", "eps_contacts": text}, ExplorerState())
        assert "stack_eps_contacts" not in values
        assert len(messages) == 1 and messages[0].startswith("URL eps_contacts:")
    values, messages = read_query({"N": "9"}, ExplorerState())
    assert values["balls"] == 3 and "from 2 to 8" in messages[0]


def test_contact_eps_asks_for_one_value_per_contact():
    from app.state import contact_eps

    assert contact_eps("", 3) == (None, None)
    assert contact_eps(" 0.9, 0.8 ,0.7", 3) == ([0.9, 0.8, 0.7], None)
    values, message = contact_eps("0.9,0.8", 3)
    assert values is None and "give 3 values for 3 balls (floor, 1-2, 2-3); got 2" in message


def test_a_link_names_its_preset_while_the_drop_is_the_preset_s():
    """A shared link kept the preset's drop but lost its name and sources: the link names the
    preset while the drop is still the preset's, and a link naming it shows it again."""
    state = ExplorerState()
    state.param.update(**preset_drop("tennis"), preset="tennis", units="SI")
    query = url_query(state)
    assert query["preset"] == "tennis"
    values, messages = read_query(query, ExplorerState())
    assert values["preset"] == "tennis" and messages == []
    state.mu = 0.05  # a moved slider: no longer the preset (the controls forget it too)
    assert "preset" not in url_query(state)
    values, messages = read_query(query | {"mu": "0.05"}, ExplorerState())
    assert "preset" not in values and values["mu"] == 0.05
    assert messages == ["URL preset: the drop in the link is not the tennis preset's; showing "
                        "the link's drop."]  # fmt: skip
    values, messages = read_query({"preset": "ping-pong"}, ExplorerState())  # a bare preset
    assert values == preset_drop("ping-pong") | {"preset": "ping-pong", "units": "SI"}
    values, messages = read_query({"preset": "golf"}, ExplorerState())
    assert "preset" not in values
    assert messages == ["URL preset: must be one of tennis, ping-pong; got 'golf'."]


def test_a_typed_decimal_comma_is_refused_with_how_to_write_it():
    """A typed "0,5" keeps the value in use, and the message says to write a point (its own
    "Keeping 9,949 m" had read as a decimal comma accepted); a typo without a comma does not
    get that advice."""
    value, message = typed_value("0,5", 9949.0, 1.0, 1e4, "H", unit=" m")
    assert value == 9949.0 and "got '0,5'" in message and "with a point: 0.5" in message
    value, message = typed_value("abc", 9949.0, 1.0, 1e4, "H", unit=" m")
    assert value == 9949.0 and "point" not in message
