"""Scene 3, the delayed-rebound map: a slice of a shipped cube at the eps nearest the drop's.

A heat map over mu and tau_d/tau_f (both logarithmic) of the chosen variable, the delayed
rebounds (h2 > h1) outlined, the current parameters starred; a click sets mu and tau_d/tau_f
to the computed cell nearest it. The slices, computed slices (another H or eps12, or an eps
outside the cube) and outlines are app/map_slices.py's; this module draws them, with Bokeh
directly, and says in its note which one is shown.

With the Hertz force (state ``map_force``) the map shows a slice of the shipped two-ball Hertz
cube whose H is nearer the drop's; nothing is computed (a Hertz drop costs about a
millisecond, a slice seconds), and the note says that H is in the Hertz length unit and that
tau_ratio counts the Hertz floor contact.

The map cube's map is one image on log10 coordinates (its mu and tau_ratio are evenly spaced
in log10), not a mesh of ~6000 cells: the browser repaints the whole plot whenever the marker
moves, and one image repaints in a fraction of the time (a slider move took ~320 ms with the
mesh). The Hertz cubes' (evenly spaced in the values) is one rectangle per cell, 2500 of them
(:func:`map_slices.drawn_as_cells`): as an image it needed 177 x 227 pixels, all sent again on
every eps move (160 kB a browser), where the cells' values are 10 kB. Both send their values
as uint16 codes (each a value to three significant digits, the hover's), and the cells are
placed in the browser (app/map_browser.py says why).
"""

from __future__ import annotations

import io
import math

import numpy as np
import panel as pn
import param
import xarray as xr
from bokeh.events import Tap
from bokeh.models import (
    BasicTicker,
    BasicTickFormatter,
    ColorBar,
    ColorMapper,
    ColumnDataSource,
    CustomJSTickFormatter,
    FixedTicker,
    Image,
    LinearColorMapper,
    LogColorMapper,
    MultiLine,
    NoOverlap,
    Quad,
    Range1d,
    Scatter,
)
from bokeh.palettes import RdBu, interp_palette, viridis
from bokeh.plotting import figure

from twoball import warmup

from .controls import PhoneSliders, on_a_phone
from .map_browser import LOG_TICK_JS, cell_edge, decoded_cells, decoded_image, values_hover
from .map_slices import (
    COUNTS,
    CUBE,
    HERTZ_CUBES,
    NO_CODE,
    RATIO_CENTRES,
    cell_edges,
    computed_slice,
    cube_colour_limits,
    drawn_as_cells,
    eps_slice,
    hertz_cube_name,
    log_grid,
    map_cube,
    nearest_eps,
    nearest_on_log_axis,
    outline_of,
    shown_cube,
    shown_label,
    slice_cells,
    slice_image,
    variable_label,
)
from .scene import (
    PROJECTOR_LINE_WIDTH,
    AnsweringMarkdown,
    Scene,
    answers_pending,
    draw,
    for_a_room,
    later,
    on_screen,
    readable,
    wrapping_row,
)
from .state import MAP_COLOURS, validate
from .worksheet import slice_csv

PROJECTOR_MAP_HEIGHT = 490  # presentation mode (scene.py): both axes and the colour bar in 720 px,
# under a lesson step's one-line answer too (560 px ran below the screen there)
# the map's eps: a drop whose eps lies outside a shipped cube's is computed at its eps rounded
# to this (once the solver is compiled), every session moving there sharing the few slices
COMPUTED_EPS_STEP = 0.01
# ... down to this eps: below it a slice's ~6000 drops, each contact barely bouncing, took the
# server 0.5 s (eps 0.08) to 2 s (0.01), every session waiting (0.14 s at 0.12; 0.08 s at 0.3)
LOWEST_COMPUTED_EPS = 0.1
# cells whose ratio is undefined (an apex below 0, the height at which the balls first touch):
# grey, not the colour of a ratio (a negative h1 had read as "h2 far below h1", dark blue)
NO_RATIO = "#9a9a9a"
# the map's style on a laptop, desktop or phone: beside the choices where the screen is wide
# enough (below them, the 640 px map of a 1366x768 laptop needed scrolling to see its lower
# half), and as tall as the window leaves under the header and tabs, at most 640 px
SIDE_STYLES = {"flex": "0 1 300px"}
FIT_STYLES = {
    "height": "clamp(380px, calc(100vh - 190px), 640px)",
    "flex": "1 1 560px",
    "min-width": "0",
}
# colour-bar ticks of the ratios' log scale: values below 1 get numbers too (LogTicker: powers
# of ten only, so a range of 0.5 to 2 showed "1" alone)
RATIO_TICKS = [0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1, 1.4, 2, 3, 5, 10, 20, 50, 100]
SHADES = 256  # the colours of a continuous scale (a ratio's, viridis)
# a ratio's colours: ColorBrewer's RdBu, blue below 1 and red above, in 256 shades
RATIO_PALETTE = interp_palette(RdBu[11], SHADES)
NO_VALUE = "rgba(0, 0, 0, 0)"  # a cell without a value (a drop without a second bounce)


def ratio_colorbar() -> dict:
    """Colour-bar options of a ratio: a FixedTicker shows the ticks inside the colour range
    (new models each time: a Bokeh model belongs to one session's document)."""
    return {"ticker": FixedTicker(ticks=RATIO_TICKS), "formatter": BasicTickFormatter()}


def count_palette(low: float, high: float) -> list[str]:
    """One colour for each whole number from ``low + 0.5`` to ``high - 0.5`` (a count's colour
    limits, :func:`colour_limits`): each count a band of its own, centred on its tick."""
    return list(viridis(max(1, round(high - low))))


def count_ticker() -> BasicTicker:
    """A count's colour-bar ticks: whole numbers only, each count's up to a dozen (a new model
    each time, as :func:`ratio_colorbar`)."""
    return BasicTicker(min_interval=1, desired_num_ticks=12)


def _log_ticks(cube: xr.Dataset) -> dict[str, list[float]]:
    """Ticks at 1, 2 and 5 times the powers of ten inside each log axis (log10 values), each
    labelled by :data:`LOG_TICK_JS`. Powers of ten alone left a zoomed map with one label per
    axis, or none."""
    ticks = {}
    for name in ("mu", "tau_ratio"):
        logs = np.log10(cube[name].values)
        decades = range(math.floor(logs.min()) - 1, math.ceil(logs.max()) + 1)
        values = [math.log10(m * 10.0**d) for d in decades for m in (1, 2, 5)]
        ticks[name] = [v for v in values if logs.min() - 1e-9 <= v <= logs.max() + 1e-9]
    return ticks


def image_frame(log_mu: np.ndarray, log_tau: np.ndarray) -> dict[str, list[float]]:
    """Where an image of pixel centres ``log_mu`` x ``log_tau`` (evenly spaced) lies: its
    lower left corner and its width and height, half a pixel beyond the outer centres."""
    frame = {}
    for (corner, size), centres in ((("x", "dw"), log_mu), (("y", "dh"), log_tau)):
        pixel = (centres[-1] - centres[0]) / max(centres.size - 1, 1)
        frame[corner] = [float(centres[0] - pixel / 2)]
        frame[size] = [float(centres[-1] - centres[0] + pixel)]
    return frame


def blank(cube: xr.Dataset, cells: bool) -> dict:
    """The figure's codes before a slice is shown (the map off screen): an image without a
    value on the cube's grid and where it lies, or the cells' codes, none (the browser places
    the cells: app/map_browser.py)."""
    if cells:
        return {"value": np.full(cube.sizes["mu"] * cube.sizes["tau_ratio"], NO_CODE, np.uint16)}
    log_mu, log_tau = log_grid(cube["mu"].values)[0], log_grid(cube["tau_ratio"].values)[0]
    codes = np.full((log_tau.size, log_mu.size), NO_CODE, np.uint16)
    return {**image_frame(log_mu, log_tau), "image": [codes]}


def outline_data(xs: np.ndarray, ys: np.ndarray) -> dict[str, list[np.ndarray]]:
    """An outline (:func:`outline_path`) as the data of a MultiLine: one line, its pieces
    separated by NaN, or none."""
    return {"xs": [on_screen(xs)], "ys": [on_screen(ys)]} if xs.size else {"xs": [], "ys": []}


def colour_mapper(variable: str, clim: tuple[float, float] | None) -> ColorMapper:
    """The image's colours: a ratio red above 1 and blue below on a log scale, a count a
    colour each (:func:`count_palette`), anything else viridis; cells without a value
    transparent."""
    if variable in RATIO_CENTRES:
        low, high = clim or (0.5, 2.0)  # (a log scale needs limits)
        return LogColorMapper(palette=RATIO_PALETTE, low=low, high=high, nan_color=NO_RATIO)
    if clim is None:  # (no slice yet: its range and bands come with it, _push_slice)
        return LinearColorMapper(palette=viridis(SHADES), nan_color=NO_VALUE)
    palette = count_palette(*clim) if variable in COUNTS else viridis(SHADES)
    return LinearColorMapper(palette=palette, low=clim[0], high=clim[1], nan_color=NO_VALUE)


def colour_bar(variable: str, mapper: ColorMapper, presentation: bool) -> ColorBar:
    """The colour bar, titled with the variable's name: ticks inside a ratio's range, whole
    numbers for a count (:func:`ratio_colorbar`, :func:`count_ticker`)."""
    if variable in RATIO_CENTRES:
        ticks = ratio_colorbar()
    elif variable in COUNTS:
        ticks = {"ticker": count_ticker()}
    else:
        ticks = {"ticker": BasicTicker()}
    sizes = ("16pt", "18pt") if presentation else ("10pt", "11pt")
    return ColorBar(
        color_mapper=mapper,
        title=shown_label(variable),
        orientation="vertical" if presentation else "horizontal",
        major_label_text_font_size=sizes[0],
        title_text_font_size=sizes[1],
        label_standoff=8,
        major_tick_line_color="black",
        bar_line_color="black",
        **ticks,
    )


class MapScene(Scene):
    """Heat map of one eps slice of the cube; a click moves mu and tau_d/tau_f."""

    variable = param.Selector(
        default="h2_over_h1", objects=list(MAP_COLOURS), doc="The quantity coloured on the map."
    )
    moved = param.Event(doc="mu or tau_ratio changed while the map is on screen: the star moves.")

    watched = (*Scene.watched, "map_force")

    def __init__(self, **params):
        super().__init__(**params)
        self.slice: xr.Dataset | None = None
        self.slice_eps = float("nan")
        self.slice_cube = ""  # the cube the slice is of (or computed on the axes of)
        self.computed = False  # the slice was computed for this drop (not the cube's)
        self.error: str | None = None
        self.choice = pn.widgets.Select(
            label="Colour by",
            options={shown_label(v): v for v in MAP_COLOURS},
            value=self.variable,
            width=270,  # (within the 300 px column beside the map)
            stylesheets=for_a_room(self.state.presentation),
        )
        self.choice.link(self, value="variable")
        # the variable is the state's, which a link carries (map_colour), and the choice shows it
        self.variable = self.choice.value = self.state.map_colour
        self.param.watch(self._variable_chosen, "variable")
        self.state.param.watch(lambda event: setattr(self, "variable", event.new), "map_colour")
        self.force = pn.widgets.RadioButtonGroup.from_param(  # (no tooltip: see app/stack.py)
            self.state.param.map_force, name="force", width=160, description=None
        )
        self.download = pn.widgets.FileDownload(  # written when clicked
            callback=self._csv, filename="map.csv", label="Download this map (CSV)", embed=False
        )
        self.note = AnsweringMarkdown(  # (rewritten with every slice and star move)
            pn.bind(self._note, self.param.revision, self.param.moved, self.param.active),
            sizing_mode="stretch_width",
        )
        # the star (current mu, tau_ratio): a glyph of its own on the figure, moved by its data
        # alone. Each figure gets a source of its own (:meth:`_map_figure`): one shared by an
        # old and a new figure was, in the browser, dropped with the old one ("reference ...
        # isn't known" on the next move).
        self.star: ColumnDataSource | None = None
        # the Bokeh models of the figure on screen that a new slice changes (_push_slice), and
        # what that figure was drawn for (its variable and cube)
        self._image_source: ColumnDataSource | None = None
        self._cell_source: ColumnDataSource | None = None  # (the Hertz cubes': drawn_as_cells)
        self._colour_mapper: ColorMapper | None = None
        self._outline_source: ColumnDataSource | None = None
        self._drawn_for: tuple[str, str] | None = None
        # a new figure per variable (its colour scale and label change) and per cube (the
        # Hertz cubes' axes are not the map cube's); within one, its models follow the state
        self.figure = pn.pane.Bokeh(None, sizing_mode="stretch_width")

    def _variable_chosen(self, event: param.parameterized.Event) -> None:
        self.state.map_colour = self.choice.value = event.new

    def cube_name(self) -> str:
        """The shipped cube shown: the map cube, or the Hertz cube nearest the drop's H."""
        if self.state.map_force == "hertz":
            return hertz_cube_name(self.state.height)
        return CUBE

    def _map_figure(self) -> figure:
        """The map's Bokeh figure for the current variable and cube: the slice's image (a
        blank on the cube's grid while off screen), the delayed rebounds' outline, the star,
        the colour bar, a hover giving mu and tau_d/tau_f as numbers, and a click setting them.

        Drawn with Bokeh directly. Through HoloViews (an Image and Contours overlay in
        DynamicMaps) the map's page cost about 190 ms of server CPU to open and its first
        document 62 kB; the drop's, drawn so, 110 ms and 36 kB (benchmarks/app_open.py)."""
        variable, name = self.variable, self.cube_name()
        cube = shown_cube(name)
        cells = drawn_as_cells(cube)  # (the Hertz cubes': one rectangle per cell)
        if self.active:
            self.current()
        if self.active and self.slice is not None:
            data, clim = self._shown(cells)
            xs, ys = self._outline_of_slice()
        else:  # (the plot keeps its frame: a later slice fills it, _push_slice)
            data, clim = blank(cube, cells), None
            xs = ys = np.zeros(0)
        if cells:
            spans = [cell_edges(cube[axis].values)[[0, -1]] for axis in ("mu", "tau_ratio")]
        else:
            spans = [
                (data[at][0], data[at][0] + data[size][0])
                for at, size in (("x", "dw"), ("y", "dh"))
            ]
        presentation = self.state.presentation
        hover = values_hover(shown_label(variable), cube, cells)
        fig = figure(
            x_range=Range1d(*map(float, spans[0])),
            y_range=Range1d(*map(float, spans[1])),
            x_axis_label="mu = m2/m1 (log scale)",
            y_axis_label="tau_d/tau_f (log scale)",
            tools=[hover, "wheel_zoom", "save", "pan", "box_zoom", "reset", "tap"],
            active_drag="pan",
            active_scroll="wheel_zoom",
            toolbar_location="right" if presentation else "above",
            sizing_mode="stretch_width",
            # (with its colour bar; else the window's height: FIT_STYLES)
            height=PROJECTOR_MAP_HEIGHT if presentation else None,
            min_height=None if presentation else 380,
            min_border=10,
            outline_line_color="#e5e5e5",
        )
        if not presentation:
            fig.styles = FIT_STYLES
        fig.grid.grid_line_color = None
        ticks = _log_ticks(cube)
        for axis, along in ((fig.xaxis, "mu"), (fig.yaxis, "tau_ratio")):
            axis.ticker = FixedTicker(ticks=ticks[along])
            axis.formatter = CustomJSTickFormatter(code=LOG_TICK_JS)
            axis.major_label_policy = NoOverlap()
        mapper = colour_mapper(variable, clim)
        source = ColumnDataSource(data)
        if cells:  # (edged in their own colour: unedged, light seams showed)
            colour = decoded_cells(mapper)
            edges = {
                side: cell_edge(cube, axis, upper)
                for side, axis, upper in (("left", "mu", False), ("right", "mu", True),
                                          ("bottom", "tau_ratio", False),
                                          ("top", "tau_ratio", True))
            }  # fmt: skip
            glyph = Quad(**edges, fill_color=colour, line_color=colour, line_width=1)
        else:
            glyph = Image(
                image=decoded_image(), x="x", y="y", dw="dw", dh="dh", color_mapper=mapper
            )
        self._image_source, self._cell_source = (None, source) if cells else (source, None)
        values = draw(fig, glyph, source)
        if cells:  # (a click selects the rectangle it lands in: the others not faded)
            values.nonselection_glyph = glyph
        hover.renderers = [values]  # (the outline and the star have no value)
        self._outline_source = ColumnDataSource(outline_data(xs, ys))
        width = PROJECTOR_LINE_WIDTH if presentation else 1.5
        draw(
            fig,
            MultiLine(xs="xs", ys="ys", line_color="black", line_width=width),
            self._outline_source,
        )
        readable(fig, presentation)
        self.star = ColumnDataSource(self._star_position())
        answers_pending(self.star)
        star = Scatter(
            x="x", y="y", marker="star", size=26, line_width=2, fill_color="yellow",
            line_color="black",
        )  # fmt: skip
        draw(fig, star, self.star)
        fig.add_layout(
            colour_bar(variable, mapper, presentation), "right" if presentation else "below"
        )
        fig.on_event(Tap, self._tapped)
        self._colour_mapper = mapper
        self._drawn_for = (variable, name)
        return fig

    def _state_changed(self, *events: param.parameterized.Event) -> None:
        if {e.name for e in events} <= {"mu", "tau_ratio"}:
            if self.active:  # (on the next tick: a click on the map lands here unlocked)
                later(self._move_star)
            return
        super()._state_changed(*events)

    def _redraw(self) -> None:
        if self.active:  # back on screen: the star to where mu and tau_ratio went meanwhile
            self._move_star()
        super()._redraw()

    def _star_position(self) -> dict[str, list[float]]:
        """The current mu and tau_ratio where the map draws them (log10)."""
        return {"x": [math.log10(self.state.mu)], "y": [math.log10(self.state.tau_ratio)]}

    def _move_star(self) -> None:
        """The star to the current mu and tau_ratio, and the note.

        Only a real move is sent. Bokeh sends a new ``data`` even when equal, and on the map's
        first visit that change reached the browser before the figure holding the star did
        (built with the star already in place by :meth:`_map_figure`): "reference ... isn't
        known" in the browser's console."""
        position = self._star_position()
        if self.star is not None and dict(self.star.data) != position:
            self.star.data = position
        self.moved = True

    @param.depends("revision", "variable", watch=True)
    def _draw_slice(self) -> None:
        """The slice on screen: pushed into the figure's models where it fits them, else drawn
        in a new figure (another variable or cube, or no figure yet)."""
        if self.active and self._layout is not None and not self._push_slice():
            self.figure.object = self._map_figure()

    def _push_slice(self) -> bool:
        """Send the current slice's values, colour range and outline to the figure's Bokeh
        models; False if they do not fit (no figure drawn yet, or one of another variable or
        grid), where a new figure must be drawn.

        The figure's frame (axes, ranges, colour bar, hover, tap) does not change with the
        slice, only these three models' values do: an eps move sends them alone."""
        source, mapper = self._image_source or self._cell_source, self._colour_mapper
        if source is None or mapper is None or self._outline_source is None:
            return False
        if self._drawn_for != (self.variable, self.cube_name()):
            return False
        self.current()
        if self.slice is None:
            return False
        cells = source is self._cell_source
        data, clim = self._shown(cells)
        if cells:  # the cells' codes alone (the browser places them): 5 kB, an image's 160
            if len(source.data["value"]) != len(data["value"]):
                return False
            source.data["value"] = data["value"]
        else:
            (drawn,) = source.data["image"]
            (shown,) = data["image"]
            if drawn.shape != shown.shape or any(
                source.data[k] != data[k] for k in ("x", "y", "dw", "dh")
            ):
                return False
            source.data = data
        # (a count's bands, one a count: their number follows the slice's)
        bands = {"palette": count_palette(*clim)} if self.variable in COUNTS else {}
        mapper.update(low=clim[0], high=clim[1], **bands)
        self._outline_source.data = outline_data(*self._outline_of_slice())
        return True

    def _shown(self, cells: bool) -> tuple[dict, tuple[float, float]]:
        """The current slice as the data of the figure's values (the image's codes and where it
        lies, or the cells' codes alone: :func:`slice_cells`), and its colour limits."""
        if cells:
            codes, clim = slice_cells(self.slice, self.variable, self._limits())
            return {"value": codes}, clim
        (log_mu, log_tau, codes), clim = slice_image(self.slice, self.variable, self._limits())
        return {**image_frame(log_mu, log_tau), "image": [codes]}, clim

    def inputs(self) -> tuple:
        """What the slice depends on: the drop's eps, H and eps12, the cube (force), the
        variable, and whether the solver is compiled (a drop not the cube's is computed only
        then). Not mu and tau_ratio, which only move the star; not the units.

        (The variable and the cube are read here, not heard of: a new figure's first frame,
        whose ranges the plot keeps, is drawn before the scene hears of the change.)"""
        s = self.state
        compiled = warmup.in_use("two-ball")
        return (s.eps, s.eps12, s.height, self.cube_name(), self.variable, compiled)

    def _is_cube_drop(self) -> bool:
        """Whether the current drop's H and eps12 are the cube's (else a slice is computed)."""
        return self.state.height == map_cube().attrs.get("height") and self.state.eps12 is None

    def _limits(self) -> tuple[float, float] | None:
        """The colour limits of the shown cube's variable over all its eps; None for a slice
        computed for another drop (its own: its values may lie outside the cube's)."""
        return None if self.computed else cube_colour_limits(self.slice_cube, self.variable)

    def _why_not_computed(self, name: str) -> str:
        """Why a drop outside the cube's eps is not computed (the end of a sentence)."""
        if name != CUBE:
            return " (the Hertz maps are not computed here)."
        if self.state.eps < LOWEST_COMPUTED_EPS - 1e-9:
            return f" (maps are computed down to eps = {LOWEST_COMPUTED_EPS:g})."
        return " (the solver is still being compiled)."

    def _star_value(self) -> str:
        """The shown value at the star (the computed cell nearest it), for a screen without a
        hover (a phone's tap showed none; a projected hover is too small for a room); empty
        with the star off the map."""
        if self.slice is None:
            return ""
        cell = {}
        for name in ("mu", "tau_ratio"):
            values = self.slice[name].values
            at = getattr(self.state, name)
            if not values.min() <= at <= values.max():
                return ""
            cell[name] = nearest_on_log_axis(values, math.log10(at))
        value = float(self.slice[self.variable].isel(cell))
        if self.variable in RATIO_CENTRES and not value > 0:
            shown = "none (an apex below 0, or missing)"
        else:
            shown = f"{value:.3f}" if abs(value) >= 0.01 else f"{value:.3g}"
        mu, tau = (float(self.slice[k][cell[k]]) for k in ("mu", "tau_ratio"))
        return (
            f"At the star (mu = {mu:.3g}, tau_d/tau_f = {tau:.3g}): "
            f"**{shown_label(self.variable)} = {shown}**."
        )

    def _eps_outside(self) -> bool:
        """Whether the drop's eps lies outside the shown cube's (both run from 0.5 to 1)."""
        values = shown_cube(self.cube_name())["eps"].values
        return not values.min() - 1e-9 <= self.state.eps <= values.max() + 1e-9

    def _computable(self) -> bool:
        """Whether a slice is computed for this drop: the map cube's axes, another H or eps12
        or an eps outside the cube (not below :data:`LOWEST_COMPUTED_EPS`), once compiled."""
        if not warmup.in_use("two-ball") or self.state.eps < LOWEST_COMPUTED_EPS - 1e-9:
            return False
        return not self._is_cube_drop() or self._eps_outside()

    def update(self) -> None:
        s = self.state
        try:
            name = self.slice_cube = self.cube_name()
            self.slice_eps = nearest_eps(s.eps, name)
            # (a shipped Hertz cube is never computed here)
            self.computed = name == CUBE and self._computable()
            if self.computed and self._eps_outside():  # (a shared slice near the drop's eps)
                rounded = round(s.eps / COMPUTED_EPS_STEP) * COMPUTED_EPS_STEP
                self.slice_eps = round(max(rounded, COMPUTED_EPS_STEP), 6)
            if self.computed:
                whole = computed_slice(self.slice_eps, s.height, s.eps12)
                self.slice = whole[[self.variable, "delayed_rebound"]]
            else:
                self.slice = eps_slice(self.slice_eps, self.variable, name)
            source = "computed" if self.computed else name
            self.download.filename = f"map-{source}-{self.variable}-eps{self.slice_eps:g}.csv"
            self.error = None
        except (OSError, ValueError, KeyError) as error:
            self.slice, self.error = None, f"The map cube could not be read: {error}"

    def _note(self, *_changes: object) -> str:
        """What the map shows and how to read it (bound to revision, moved and active)."""
        if not self.active:
            return ""  # off screen: nothing is computed
        self.current()
        if self.error:
            return f"**{self.error}**"
        name = self.cube_name()
        cube = shown_cube(name)
        attrs = cube.attrs
        s = self.state
        eps12 = "eps" if s.eps12 is None else f"{s.eps12:g}"
        if name != CUBE:
            heights = " and ".join(f"{h:g}" for h in HERTZ_CUBES)
            source = (
                f"**Hertz force**: precomputed map {name} at **eps = "
                f"{self.slice_eps:g}** (nearest to {s.eps:g}), **H = {attrs.get('height'):g} in "
                "the Hertz length unit** L = (m1 g / k_h)^(2/3) (of the shipped H = "
                f"{heights}, the nearest to this drop's H = {s.height:g}), eps12 = eps; "
                "**tau_d/tau_f counts the Hertz floor contact time** at that H"
            )
        elif self.computed and self._eps_outside():
            low, high = float(cube["eps"].min()), float(cube["eps"].max())
            source = (
                f"Computed for this drop at **eps = {self.slice_eps:g}** (the precomputed "
                f"maps run from eps = {low:g} to {high:g}; this drop's eps is {s.eps:g}), "
                f"**H = {s.height:g}, eps12 = {eps12}**"
            )
        elif self.computed:
            source = (
                f"Computed for this drop at **eps = {self.slice_eps:g}** (the map's eps "
                f"nearest to {s.eps:g}), **H = {s.height:g}, eps12 = {eps12}**"
            )
        else:
            source = (
                f"Precomputed map at **eps = {self.slice_eps:g}** (nearest to "
                f"{s.eps:g}), H = {attrs.get('height'):g}, eps12 = eps"
            )
        click = "Click the map to set mu and tau_d/tau_f."
        if name != CUBE:  # (a new user clicked here and read a linear drop as this map's)
            click = (
                "Click the map to set mu and tau_d/tau_f for the other scenes, whose drops "
                "use the **linear** force (the Stack scene offers the Hertz force)."
            )
        projected = self.state.presentation
        grey = ""
        ratio = self.variable in RATIO_CENTRES and self.slice is not None
        if ratio and (~(self.slice[self.variable].values > 0)).any():
            grey = "grey: no ratio; " if projected else (
                "grey: no ratio (an apex below 0, where the balls first touch, or none); "
            )  # fmt: skip
        # (on a projector the teacher says the rest and clicks: the whole note ran below a
        # 720 px screen)
        why = (
            ""
            if projected
            else "; its holes, islands and odd single cells are real: mostly where one brief "
            "contact more or fewer happens, h2 jumps"
        )
        lines = [
            f"{source}. Black outlines: delayed rebound (h2 > h1{why}); {grey}"
            "star: current parameters." + ("" if projected else " " + click)
        ]
        if self._eps_outside() and not self.computed:
            low, high = float(cube["eps"].min()), float(cube["eps"].max())
            lines.append(
                f"**The current eps = {s.eps:g} lies outside the map** (eps = {low:g} to "
                f"{high:g}): it shows eps = {self.slice_eps:g}, not this drop"
                + self._why_not_computed(name)
            )
        lines[:0] = self._off_the_map(cube)  # (first: under the rest, a phone showed it last)
        star = self._star_value()
        if star:
            lines.append(star)
        if cube is not map_cube():
            if s.eps12 is not None:
                lines.append(
                    f"The Hertz cubes have eps12 = eps: the drop's eps12 = {eps12} is not shown."
                )
        elif not self.computed and not self._is_cube_drop():
            lines.append(
                f"The current drop (H = {s.height:g}, eps12 = {eps12}) differs from the "
                "cube's, and the solver is still being compiled: the map shows the cube's "
                "until it is."
            )
        return "  \n".join(lines)

    def _off_the_map(self, cube) -> list[str]:
        """What a teacher reads where the current mu or tau_d/tau_f lies off the map: that the
        star is not on it, past which edge and why (the slider's mu runs to 10, the map's to 1:
        "the star is off the map" alone left a teacher looking for it), and how to bring it
        back."""
        s = self.state
        lines = []
        for key, what, edges in (
            ("mu", "mu", ("left", "right")),
            ("tau_ratio", "tau_d/tau_f", ("bottom", "top")),
        ):
            low, high = float(cube[key].min()), float(cube[key].max())
            value = getattr(s, key)
            if low <= value <= high:
                continue
            above = value > high
            edge, back = edges[above], f"{high:g} or less" if above else f"{low:g} or more"
            heavier = ""
            if key == "mu" and value > 1 >= high:
                heavier = (
                    f", an upper ball at most as heavy as the lower one; this one is {value:g} "
                    "times heavier"
                )
            if s.presentation:  # (the teacher says the rest: the note ran below 720 px)
                lines.append(
                    f"**No star: {what} = {value:g} is off the map** ({low:g} to {high:g})."
                )
                continue
            lines.append(
                f"**No star: {what} = {value:g} is off the map**, past its {edge} edge (the map "
                f"shows {what} = {low:g} to {high:g}{heavier}). The other tabs show this drop; "
                f"set {what} to {back} to see it on the map."
            )
        return lines

    def _outline_of_slice(self) -> tuple[np.ndarray, np.ndarray]:
        s = self.state
        drop = (s.height, s.eps12) if self.computed else None
        return outline_of(self.slice_cube, self.slice_eps, drop)

    def _csv(self) -> io.StringIO:
        """The slice on screen for a worksheet (app/worksheet.py)."""
        self.current()
        if self.slice is None:  # (the note says why)
            return io.StringIO(f"# {self.error}\n")
        s = self.state
        name = self.cube_name()
        shipped = "the shipped map cube" if name == CUBE else f"the shipped Hertz cube {name}"
        about = {
            "eps": self.slice_eps,
            "H": s.height if self.computed else shown_cube(name).attrs.get("height"),
            "eps12": (s.eps12 if self.computed else None) or "equal to eps",
            "source": "computed for this drop" if self.computed else shipped,
            "force": "linear"
            if name == CUBE
            else (
                "hertz; H in the Hertz length unit L = (m1 g / k_h)^(2/3), tau_ratio counts "
                "the Hertz floor contact time"
            ),
            "variable": variable_label(self.variable),
        }
        return io.StringIO(slice_csv(self.slice, self.variable, about))

    def _tapped(self, event: Tap) -> None:
        """A click on the map: the mu and tau_d/tau_f of the computed cell nearest it (the map
        is drawn in log10), so that the other scenes' drop is the cell's, its h2/h1 the one the
        map shows there."""
        if event.x is None or event.y is None:
            return
        cube = shown_cube(self.cube_name())
        chosen = {}
        for name, at in (("mu", event.x), ("tau_ratio", event.y)):
            values = cube[name].values
            nearest = float(values[nearest_on_log_axis(values, at)])
            chosen[name], _ = validate(name, nearest, getattr(self.state, name))
        self.state.param.update(**chosen)

    def layout(self) -> pn.viewable.Viewable:
        self.figure.object = self._map_figure()
        if self.state.presentation:  # 1280x720 (scene.py): the choices beside the map
            side = pn.Column(self.choice, self.force, self.download, self.note, width=300)
            return pn.Row(self.figure, side, sizing_mode="stretch_width")
        # the choices and the note right of the map, wrapped below it on a phone
        side = pn.Column(self.choice, self.force, self.download, self.note, styles=SIDE_STYLES)
        if on_a_phone():  # the sliders under the map, as on the Drop (a new user's trial)
            side.insert(0, PhoneSliders(state=self.state))
        return wrapping_row(self.figure, side, sizing_mode="stretch_width")
