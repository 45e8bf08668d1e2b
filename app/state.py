"""The explorer's shared state: the model's parameters plus the scene and the units shown.

No widgets here. The parameters are the model's own (:class:`twoball.model.Parameters`, declared
once with their bounds); the explorer only narrows them to the ranges its sliders can show.
Values from the URL or from an input go through :func:`validate`, which never raises: a bad
value gives a message and a valid fallback.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

import param

from twoball import presets
from twoball.model import DEFAULT_HEIGHT, Parameters, check_value
from twoball.units import number_text

from .scenes import SCENES
from .steps import STEPS

UNITS = ("dimensionless", "SI")

# Query-string keys of the parameters that the URL carries.
URL_KEYS = {"eps": "eps", "mu": "mu", "tau_ratio": "tau_ratio", "height": "H", "eps12": "eps12"}
# The Stack scene's keys: checked against the bounds its parameters declare.
STACK_URL_KEYS = {
    "balls": "N",
    "stack_ratio": "ratio",
    "stack_eps": "stack_eps",
    "stack_gap": "gap",
}


# what the delayed-rebound map can colour (app/delayed_map.py), the first by default
MAP_COLOURS = ("h2_over_h1", "h1_over_icm", "h1_over_drop", "h2_over_drop", "contacts_first")


class ExplorerState(Parameters):
    """One session's drop (the model's parameters) and what is on screen.

    The page opens on the paper's drop (docs/model.md, check values), a light ball dropped on
    a heavy one that rebounds higher the second time: a delayed rebound, worth seeing first.
    """

    # What the explorer's controls can show, inside the model's own bounds (the docs are the
    # model's): the sliders and the URL's checks read these bounds, nothing else. The defaults
    # are the opening drop, the paper's (h2 = 5.4 h1).
    eps = param.Number(0.9, bounds=(0.01, 1.0))
    eps12 = param.Number(None, allow_None=True, bounds=(0.01, 1.0))
    mu = param.Number(0.01, bounds=(1e-4, 10.0))
    tau_ratio = param.Number(0.01, bounds=(1e-4, 10.0))
    height = param.Number(DEFAULT_HEIGHT, bounds=(10.0, 1e8), inclusive_bounds=(True, True))

    preset = param.String(
        default="",
        doc="The preset chosen (a key of twoball.presets.PRESETS), empty for none; kept only "
        "while the drop is the preset's (a moved slider drops it).",
    )
    scene = param.Selector(default="drop", objects=list(SCENES), doc="The scene on screen.")
    units = param.Selector(
        default="dimensionless",
        objects=list(UNITS),
        doc="Show dimensionless X and tau, or metres and seconds (basketball, presets.py).",
    )

    step = param.Integer(
        default=0, bounds=(0, None), doc="The lesson's step on screen, 0 without the lesson."
    )
    revealed = param.Boolean(
        default=False,
        doc="Whether the lesson step's answer is revealed (until then its scene is covered).",
    )
    presentation = param.Boolean(
        default=False, doc="Large text and plots for a projector (URL: present=1)."
    )
    slider_moved = param.Event(
        doc="A slider released by the user, wherever it stands (the sidebar, or a copy under a "
        "phone's plot): the messages of a bad URL or typed value go (app/controls.py)."
    )
    # the Stack scene's drop (twoball.stacks): one mass ratio, restitution and gap for every pair
    balls = param.Integer(default=3, bounds=(2, 8), doc="Balls in the stack.")
    stack_ratio = param.Number(
        default=0.2, bounds=(0.01, 1.0), doc="Each ball's mass over the one below it."
    )
    stack_eps = param.Number(default=0.9, bounds=(0.3, 1.0), doc="Restitution of every contact.")
    stack_gap = param.Number(
        default=0.2,
        bounds=(0.01, 2.0),  # touching balls (0) cannot be carried with five or more
        doc="tau_d/tau_f between each pair: how far apart the balls are at release.",
    )
    force = param.Selector(
        default="linear", objects=["linear", "hertz"], doc="The contact force of the stack."
    )
    stack_eps_contacts = param.String(
        default="",
        doc="The Stack scene's eps per contact as typed (floor, 1-2, 2-3, ...), comma-separated; "
        "empty: stack_eps for every contact. Checked against N by the scene (contact_eps).",
    )
    # The map's force is its own, not the stack's ``force``: the map's Hertz is a lookup in the
    # two shipped two-ball Hertz cubes (their own length unit, H 1e2 or 1e4), the stack's a
    # live N-ball drop at the explorer's H; sharing one switch, choosing Hertz to look at the
    # map would silently change the Stack scene (and a Stack-scene URL would reopen the map on
    # Hertz). Each URL carries the force of its own scene (force, map_force).
    map_force = param.Selector(
        default="linear",
        objects=["linear", "hertz"],
        doc="The contact force of the delayed-rebound map (the shipped cube shown).",
    )
    map_colour = param.Selector(
        default=MAP_COLOURS[0],
        objects=list(MAP_COLOURS),
        doc="The quantity the delayed-rebound map colours (a variable of its cubes).",
    )


def app_range(name: str) -> tuple[float, float]:
    """What the explorer shows of a model parameter: (low, high), as :class:`ExplorerState`
    declares it."""
    return ExplorerState.param[name].bounds


def validate(name: str, value: object, fallback: float | None) -> tuple[float | None, str | None]:
    """(value to use, message or None) for a parameter typed or read from the URL.

    The model decides what is valid (:func:`twoball.model.check_value`); a valid value outside
    what the sliders show is clamped into :func:`app_range`. ``eps12`` may be empty or "none"
    (equal to eps). Never raises.
    """
    if name == "eps12" and (value is None or str(value).strip().lower() in ("", "none")):
        return None, None
    low, high = app_range(name)
    try:
        number = check_value(name, value)
    except ValueError:  # (the model's message quotes its own range; the explorer's is shown)
        shown = "equal to eps" if fallback is None else number_text(fallback)
        return fallback, (
            f"{name} must be a number {span(low, high)}; got {str(value)[:40]!r}. Using {shown}."
        )
    if number < low or number > high:
        clamped = min(max(number, low), high)
        return clamped, (
            f"{name} = {number_text(number)} is outside the explorer's range, {span(low, high)}; "
            f"using {number_text(clamped)}."
        )
    return number, None


def typed_value(
    text: str,
    last: float | None,
    low: float,
    high: float,
    name: str,
    unit: str = "",
    shown: Callable[[float], str] | None = None,
) -> tuple[float | None, str | None]:
    """(value to use, message or None) for a number typed under "advanced" (the drop height,
    in H or metres, and eps12), by one rule:

    - a number outside ``low``..``high`` (0, -5, 1e20, an eps12 of 2, even infinity) is clamped
      to the nearest end, and the message says so (the ends and the value used as ``shown``
      writes them, if given: :func:`metres_text`, else the number and ``unit``);
    - text that is no number (or NaN) keeps ``last``, the value in use, and the message says so.

    (Before, a typed value the model refused, H = 0 or eps12 = 2, fell back while one it
    accepted, H = 1e20, was clamped: the same mistake undone or corrected by chance.) A URL's
    values are read by :func:`validate` instead: a link has no value in use to keep. Never
    raises."""
    try:
        number = float(text)
    except ValueError:
        number = math.nan
    allowed = span(low, high, unit, shown)
    if math.isnan(number):
        kept = "equal to eps" if last is None else f"{number_text(last)}{unit}"
        # (a decimal comma refused, the message's own thousands comma read as one: "got '0,5'.
        # Keeping 9,949 m", a teacher's trial)
        point = " Write decimals with a point: 0.5, not 0,5." if "," in str(text) else ""
        return last, (
            f"{name} must be a number {allowed}; got {str(text)[:40]!r}. Keeping {kept}.{point}"
        )
    if number < low or number > high:
        clamped = min(max(number, low), high)
        return clamped, (
            f"{name} {str(text).strip()[:40]}{unit} is outside the explorer's range, {allowed}; "
            f"using the nearest, {shown(clamped) if shown else number_text(clamped) + unit}."
        )
    return number, None


def span(
    low: float, high: float, unit: str = "", shown: Callable[[float], str] | None = None
) -> str:
    """A range in words for a message a student reads ("from 0.01 to 1", not "[0.01, 1]"),
    each end written by ``shown`` if given ("from about 0.99 mm to 9.9 km")."""
    if shown is None:
        return f"from {number_text(low)}{unit} to {number_text(high)}{unit}"
    ends = [shown(low), shown(high)]
    if all(end.startswith("about ") for end in ends):  # (one "about" for both)
        ends[1] = ends[1].removeprefix("about ")
    return f"from {ends[0]} to {ends[1]}"


def metres_text(metres: float) -> str:
    """A length for a student, to two digits in mm, m or km: "about 0.99 mm", "about 9.9 km",
    "2 m". The drop height's limits in metres are the model's in H converted, 0.0009949 m and
    9,949 m, odd numbers to read; the value used stays the model's own (controls._take_height)."""
    value, unit = (
        (metres * 1e3, "mm")
        if metres < 0.01
        else (metres / 1e3, "km")
        if metres >= 1e3
        else (metres, "m")
    )
    rounded = float(f"{value:.2g}")
    about = "" if math.isclose(rounded, value, rel_tol=1e-9) else "about "
    return f"{about}{number_text(rounded)} {unit}"


def read_query(query: Mapping[str, str], defaults: Parameters) -> tuple[dict, list[str]]:
    """Parameter values and messages from a URL's query (keys :data:`URL_KEYS` and ``scene``).

    Unknown keys are ignored; each bad value falls back to its default with a message.
    """
    values: dict = {}
    messages = []
    height_message = None  # (its index, the height used)
    for name, key in URL_KEYS.items():
        if key not in query:
            continue
        value, message = validate(name, query[key], getattr(defaults, name))
        values[name] = value
        if message:
            messages.append(f"URL {key}: {message}")
            if name == "height":
                height_message = (len(messages) - 1, value)
    if "preset" in query:
        found, message = _read_preset(query["preset"], values, defaults)
        values = found | values
        if message:
            messages.append(f"URL preset: {message}")
    for name, key in STACK_URL_KEYS.items():
        if key in query:
            value, message = _stack_value(name, query[key], getattr(defaults, name, None))
            values[name] = value
            if message:
                messages.append(f"URL {key}: {message}")
    for name in ("force", "map_force", "map_colour", "units"):  # (a choice among names)
        if name in query:
            choices = ExplorerState.param[name].objects
            if query[name] in choices:
                values[name] = query[name]
            else:
                messages.append(
                    f"URL {name}: must be one of {', '.join(choices)}; got "
                    f"{query[name][:40]!r}. Using {getattr(defaults, name, choices[0])}."
                )
    if "eps_contacts" in query:
        text = query["eps_contacts"][:200]
        _, message = contact_eps(text, None, ExplorerState.param.balls.bounds[1])
        if message is None:  # (the count is checked against N by the scene)
            values["stack_eps_contacts"] = text
        else:
            messages.append(f"URL eps_contacts: {message}")
    if query.get("present") in ("1", "true", "yes"):
        values["presentation"] = True
    if "step" in query:
        text = query["step"]
        if text.isdigit() and 1 <= int(text) <= len(STEPS):
            shown = STEPS[int(text) - 1]
            # a lesson speaks metres unless the URL asks otherwise
            values |= {**shown.drop, "scene": shown.scene, "step": int(text), "preset": ""}
            values.setdefault("units", "SI")
        else:
            messages.append(
                f"URL step: must be a lesson step from 1 to {len(STEPS)}; got {text[:40]!r}."
            )
    if "scene" in query and "step" not in values:
        # in any case ("Map", as the tab's title reads, had opened the Drop: a teacher's link)
        name = query["scene"].strip().lower()
        if name in SCENES:
            values["scene"] = name
        else:
            messages.append(
                f"URL scene: must be one of {', '.join(SCENES)}; got {query['scene']!r}. "
                f"Using {defaults.scene}."
            )
    # A page in metres (units=SI, a lesson's or a preset's link) says a limited H in metres
    # too: "using 100,000,000" alone never said that the drop it shows, 9.95e+03 m, had been
    # limited to about 9.9 km (a teacher's trial)
    if height_message is not None and values.get("units", getattr(defaults, "units", "")) == "SI":
        at, height = height_message
        if values.get("height") == height:  # (not a lesson step's own drop)
            metres = metres_text(presets.metres_from_height(height))
            messages[at] += f" In metres: a drop from {metres}."
    return values, messages


def preset_drop(key: str) -> dict[str, float]:
    """The drop a preset sets: its parameters and the height of a 1 m drop."""
    preset = presets.PRESETS[key]
    height = presets.height_from_metres(presets.DEFAULT_DROP_METRES)
    drop = {name: getattr(preset, name) for name in ("eps", "eps12", "mu", "tau_ratio")}
    return drop | {"height": height}


def is_preset_drop(key: str, values: Mapping[str, float | None]) -> bool:
    """Whether ``values`` (the state's or a URL's) are the preset's drop, to the 12 digits a
    URL carries."""
    return all(
        values.get(name) is not None and math.isclose(values[name], value, rel_tol=1e-10)
        for name, value in preset_drop(key).items()
    )


def _read_preset(name: str, values: dict, defaults: Parameters) -> tuple[dict, str | None]:
    """The URL's ``preset``: its drop (and metres) for a link with no drop of its own; for a
    link with one, the preset is shown only if the drop is still the preset's."""
    if name not in presets.PRESETS:
        return {}, f"must be one of {', '.join(presets.PRESETS)}; got {name[:40]!r}."
    if not values.keys() & URL_KEYS.keys():
        return {**preset_drop(name), "preset": name, "units": "SI"}, None
    drop = {key: getattr(defaults, key) for key in URL_KEYS} | values
    if is_preset_drop(name, drop):
        return {"preset": name}, None
    return {}, f"the drop in the link is not the {name} preset's; showing the link's drop."


def _stack_value(name: str, text: str, fallback: float) -> tuple[float, str | None]:
    """A Stack scene value from the URL within its declared bounds, else the fallback and a
    message (never raises)."""
    declared = ExplorerState.param[name]
    low, high = declared.bounds
    try:
        number = float(text)
    except ValueError:
        number = float("nan")
    whole = name != "balls" or number.is_integer()
    if not (low <= number <= high and whole):
        kind = "a whole number" if name == "balls" else "a number"
        return fallback, (
            f"{name} must be {kind} {span(low, high)}; got {text[:40]!r}. Using "
            f"{number_text(fallback)}."
        )
    return (int(number) if name == "balls" else number), None


def contact_eps(
    text: str, balls: int | None, most: int | None = None
) -> tuple[list[float] | None, str | None]:
    """The Stack scene's eps per contact from comma-separated ``text`` (the floor's, then each
    pair's, bottom up): (values, None), (None, None) when empty (one eps for all), or (None, a
    message) on bad input. ``balls`` asks for exactly that many values; ``balls`` None accepts
    1 to ``most`` (the URL is read before N is known). Never raises."""
    if not text.strip():
        return None, None
    low, high = ExplorerState.param.stack_eps.bounds
    values = []
    for part in text.split(","):
        try:
            value = float(part)
        except ValueError:
            return None, f"eps per contact must be numbers separated by commas; got {part[:40]!r}"
        if not low <= value <= high:
            return None, f"each eps per contact must be {span(low, high)}; got {part.strip()}"
        values.append(value)
    if balls is not None and len(values) != balls:
        names = ", ".join(["floor"] + [f"{i}-{i + 1}" for i in range(1, balls)])
        return None, f"give {balls} values for {balls} balls ({names}); got {len(values)}"
    if balls is None and most is not None and len(values) > most:
        return None, f"give at most {most} values; got {len(values)}"
    return values, None


def url_query(state: ExplorerState) -> dict[str, str]:
    """The query string that restores ``state`` (eps12 left out when equal to eps)."""
    query = {
        key: f"{getattr(state, name):.12g}"
        for name, key in URL_KEYS.items()
        if getattr(state, name) is not None
    }
    if state.preset and is_preset_drop(state.preset, state.param.values()):
        query["preset"] = state.preset
    query["scene"] = state.scene
    if state.scene == "stack":
        query |= {key: f"{getattr(state, name):.12g}" for name, key in STACK_URL_KEYS.items()}
        query["force"] = state.force
        # only an entry the scene uses (a wrong one, which it shows as wrong, stays out of a
        # link: it was shared as eps_contacts=abc)
        if contact_eps(state.stack_eps_contacts, state.balls)[0] is not None:
            query["eps_contacts"] = state.stack_eps_contacts.strip()
    if state.scene == "map" and state.map_force != "linear":
        query["map_force"] = state.map_force
    if state.scene == "map" and state.map_colour != MAP_COLOURS[0]:
        query["map_colour"] = state.map_colour
    if state.step:
        query["step"] = str(state.step)
    if state.presentation:
        query["present"] = "1"
    if state.units != "dimensionless":
        query["units"] = state.units
    return query
