"""The explorer: controls beside one tab per scene; only the scene on screen is computed."""

from __future__ import annotations

import functools
import os
from collections.abc import Mapping
from pathlib import Path
from urllib.parse import urlencode

import panel as pn
import param
from bokeh.document import Document
from panel.io.document import init_doc
from panel.io.resources import use_cdn
from panel.io.state import set_curdoc, state

from twoball import warmup

from .controls import Controls
from .lesson import Lesson
from .scene import MODEL_PARAMETERS, PAGE_DESIGN, Built, Scene, alert, join
from .scenes import SCENE_REGISTRY, SCENES
from .state import ExplorerState, read_query, url_query

URL_DELAY_MS = 300
# a phone or a narrow window: the controls above the scenes, each the full width
PAGE_CSS = """
@media (max-width: 767px) {
  #container { height: auto !important; min-height: 100vh; overflow: visible !important; }
  #content { flex-direction: column; flex-wrap: nowrap; height: auto !important;
             overflow: visible !important; }
  #content > #main { order: 1; width: 100%; height: auto !important; max-height: none !important;
                     overflow: visible !important; flex: none !important; }
  #content > #sidebar { order: 2; max-width: 100% !important; width: 100% !important;
                        height: auto !important; flex: none !important; }
  #header .title, .title { font-size: 1.15rem !important; white-space: normal; }
  #sidebar-toggle { display: none !important; }
  #twoball-projector { display: none; }
}
#twoball-projector { margin-left: auto; margin-right: 0.5rem; color: var(--header-color);
                     font-size: 1.1rem; text-decoration: underline; }
"""
# A change the server has not answered yet (scene.PENDING_JS marks the body): after a quarter of
# a second, so that a quick answer never flickers, the scene dims and a banner says the plots
# are being updated; stale plots never look current while a busy server catches up
PENDING_CSS = """
#main { transition: opacity 0.1s; }
body.twoball-pending #main { opacity: 0.45; transition: opacity 0.2s 0.25s; }
body.twoball-pending::after {
  content: "Updating the plots…"; position: fixed; top: 72px; right: 24px; z-index: 2000;
  background: #0072B2; color: #fff; padding: 6px 14px; border-radius: 4px; font-size: 1.1rem;
  opacity: 0; animation: twoball-pending-shows 0.2s 0.25s forwards;
}
@keyframes twoball-pending-shows { to { opacity: 1; } }
"""
# On a phone (narrower than 768 px) the page scrolls as a whole (the template's container is
# one screen high and clips: the plots were out of reach), the scene comes first and the lesson
# and the controls follow it at full width. The template's menu button is hidden there: it
# folded the controls at the page's foot, out of sight, and seemed to do nothing (a teacher's
# trial); a finger scrolls to them.
# presentation mode (?present=1): large text for a room
PRESENTATION_CSS = """
:root { --bokeh-font-size: 20px; --bokeh-base-font-size: 20px; --pn-font-size: 20px; }
html, body { font-size: 20px; }
"""


TABS_CSS = """
:host(.bk-above) .bk-headers-wrapper { flex-wrap: wrap; }
:host > [aria-hidden="true"] { display: none; }
"""


class Explorer(Built):
    """One session of the app, built from a URL query (``{key: text}``)."""

    state = param.ClassSelector(class_=ExplorerState)

    def __init__(self, query: Mapping[str, str] | None = None, **params):
        state = params.pop("state", None) or ExplorerState()
        values, messages = read_query(query or {}, state)
        state.param.update(**values)  # before the scenes exist (_scene_chosen depends on it)
        super().__init__(state=state, **params)
        self.controls = Controls(state=self.state, messages=messages)
        self.lesson = Lesson(state=self.state)
        # a scene is built when first shown (its widgets, figures and Bokeh models): a page
        # costs the scene on screen, not all five (docs/performance.md, "A class at once");
        # once built it stays rendered (a re-rendered tab, dynamic=True, left Bokeh
        # ranges that no longer followed the units or a preset)
        self.scenes: dict[str, Scene] = {}
        # a scene's tab holds a column of its caption and the scene once it is built, an empty
        # spacer until then (four empty columns were 4.7 ms of a page's opening, the spacers
        # about a third of that: benchmarks/app_open.py)
        self._holders: dict[str, pn.viewable.Viewable] = {
            name: pn.Spacer(margin=0) for name in SCENE_REGISTRY
        }
        self.tabs: pn.Tabs | None = None
        shown = self.scene(self.state.scene)  # (on screen: Explorer.scene)
        self.tabs = pn.Tabs(
            *((entry.title, self._holders[name]) for name, entry in SCENE_REGISTRY.items()),
            dynamic=False,
            active=SCENES.index(self.state.scene),
            sizing_mode="stretch_width",
            # the tab titles wrap onto a second row on a narrow screen (Bokeh scrolls them
            # sideways, with no sign on a phone that two more tabs lie off screen); a hidden
            # scene takes no room: Panel hides it but keeps its place, so the page stayed as
            # tall as the tallest scene visited (a phone: 300 px of blank above the controls)
            stylesheets=[TABS_CSS],
        )
        self.tabs.param.watch(self._tab_chosen, "active")
        self.stage = self.lesson.stage()  # a step's question, in place of its covered scene
        self._cover()
        self.controls.show_scene_controls(shown.own_controls())

    def scene(self, name: str) -> Scene:
        """The scene ``name``, built (and put into its tab) the first time it is asked for."""
        if name not in self.scenes:
            self.scenes[name] = SCENE_REGISTRY[name].viewer_class()(state=self.state)
            # on screen before its tab gets it: its layout draws its data into its figures,
            # which reach the browser with them (sent empty, a figure's auto ranges had nothing
            # to fit: "could not set initial ranges" in the console, 3 on opening the Drop or
            # the Stack from its tab); its text panes are styled from the start (app.scene.Text)
            self.scenes[name].active = name == self.state.scene
            # on a projector the teacher says what the scene shows: its plots get the room
            caption = [] if self.state.presentation else [self._caption(name)]
            holder = pn.Column(*caption, self.scenes[name], sizing_mode="stretch_width")
            self._holders[name] = holder
            if self.tabs is not None:  # (the page's first scene is built before its tabs)
                self.tabs[SCENES.index(name)] = (SCENE_REGISTRY[name].title, holder)
        return self.scenes[name]

    @staticmethod
    def _caption(name: str) -> pn.pane.Markdown:
        return pn.pane.Markdown(
            SCENE_REGISTRY[name].caption,
            sizing_mode="stretch_width",
            styles={"font-style": "italic"},
        )

    def _tab_chosen(self, event: param.parameterized.Event) -> None:
        self.state.scene = SCENES[event.new]

    @param.depends("state.step", "state.revealed", watch=True)
    def _cover(self) -> None:
        """A lesson step's scene stays covered until its answer is revealed (it would give the
        answer away); it keeps computing underneath, so it shows at once."""
        covered = self.state.step > 0 and not self.state.revealed
        self.lesson.ask(covered)
        if covered:
            join(self._layout, self.stage)
        self.tabs.visible = not covered

    @param.depends("state.scene", watch=True)
    def _scene_chosen(self) -> None:
        self.controls.show_scene_controls(self.scene(self.state.scene).own_controls())
        for name, scene in self.scenes.items():
            scene.active = name == self.state.scene
        self.tabs.active = SCENES.index(self.state.scene)

    def follow_location(self, location: pn.io.location.Location) -> None:
        """Keep the browser's URL equal to the state (bad values in it are replaced at once).

        The URL is rewritten shortly after a change, once for a burst of changes: sent in the
        same update as the plots it delayed them by about 65 ms (benchmarks/app_latency.py).
        Not ``pn.state.location.sync``: that writes every change at once (each slider step of a
        drag) and reads values with Panel's own parsing, while the query here has its own short
        keys, units and validation with messages (app/state.py, ``read_query``/``url_query``).
        """
        pending = False

        def write() -> None:
            nonlocal pending
            pending = False
            location.search = "?" + urlencode(url_query(self.state))

        def changed(*events: param.parameterized.Event) -> None:
            nonlocal pending
            document = pn.state.curdoc
            if document is None or document.session_context is None:
                write()
            elif not pending:
                pending = True
                document.add_timeout_callback(write, URL_DELAY_MS)

        stack = ["balls", "stack_ratio", "stack_eps", "stack_gap", "force", "stack_eps_contacts"]
        watched = [
            *MODEL_PARAMETERS,
            "preset",
            "scene",
            "units",
            "step",
            "map_force",
            "map_colour",
            *stack,
        ]
        self.state.param.watch(changed, watched)
        pn.state.onload(write)  # once the browser has reported its own URL

    @staticmethod
    def _compiling_notice() -> list[pn.pane.Alert]:
        """A note on a page opened while the server's first start compiles the solver."""
        if warmup.in_use("two-ball"):  # (a stack's solver follows 2 minutes later)
            return []
        text = (
            "First start on this machine: the solver is still being compiled (a minute or two, "
            "more on a busy machine). "
            "Until then drops are computed in plain Python: the same results, a little slower."
        )
        return [alert(text, alert_type="info", sizing_mode="stretch_width")]

    def sidebar(self) -> pn.Column:
        """The controls (and a note while the solver compiles), for the page's sidebar.

        On a projector the lesson card (its title, the answer's explanation, its buttons)
        comes first, then the sliders, within the screen's 720 px until the lesson starts; the
        lesson's question is shown large in the main area, and the notice, which matters less
        than the sliders the class watches, comes last."""
        if self.state.presentation:
            parts = [self.lesson, self.controls, *self._compiling_notice()]
        else:
            parts = [*self._compiling_notice(), self.lesson, self.controls]
        return pn.Column(*parts, sizing_mode="stretch_width")

    def layout(self) -> pn.viewable.Viewable:
        """The scenes, below a lesson step's question that covers them until its answer
        (the controls go into the page's sidebar, :meth:`page`)."""
        # the question joins the page when a step first covers the scene (_cover): empty, in
        # every page's first document, it cost a page opened without the lesson
        parts = [self.stage] if self.state.step else []
        controls = self.controls
        if controls.messages_above_scenes and controls.url_message_shown():
            parts.insert(0, controls.message)  # (a phone: Controls.messages_at)
        layout = pn.Column(*parts, self.tabs, sizing_mode="stretch_width")
        if controls.messages_above_scenes:
            controls.messages_at = layout
        return layout

    def page(self) -> ClassroomPage:
        """The served page: the controls in a sidebar that folds away (the button top left),
        the scenes in the main area, under a header; on a narrow screen the controls stack
        below the scenes (PAGE_CSS)."""
        return ClassroomPage(self.sidebar(), self, presentation=self.state.presentation)


TITLE = "Two-ball bounce explorer"


@functools.cache
def page_shell(presentation: bool, rel_path: str, cdn: bool) -> pn.template.BootstrapTemplate:
    """Panel's Bootstrap page as this app's pages have it, made once per process (for each
    way of presenting and of serving resources): its Jinja template (app/static/classroom.html),
    its variables, its design and the style sheets and scripts it loads are the same for every
    page. BootstrapTemplate, not FastListTemplate: the latter loads a font from Google, and the
    app must not reach the network."""
    shell = _ClassroomTemplate(
        title=TITLE,
        design=PAGE_DESIGN,  # (a text pane's own: app.scene.Text)
        sidebar=[pn.Column()],  # (a page has a sidebar: the template's menu button)
        sidebar_width=330,
        header_background="#0072B2",
        meta_viewport="width=device-width, initial-scale=1",
    )
    shell.config.raw_css.extend([PAGE_CSS, PENDING_CSS])
    if presentation:
        shell.config.raw_css.append(PRESENTATION_CSS)
    shell._update_vars()
    return shell


class ClassroomPage:
    """A session's page: its sidebar and its main area put into the session's document as the
    two roots of Panel's Bootstrap page (:func:`page_shell`), beside the location.

    Not a Panel template object for each page: BootstrapTemplate made, for every page, its lists,
    its config, a notebook view, a busy spinner and a common root through which Panel's
    preprocessing links components across the roots (this page has no such link: its
    callbacks are Bokeh's own, on each model), and gave the same Jinja template and variables
    each time: 12 ms of a page's opening, of 93 (benchmarks/app_open.py, paired). What a page
    does here is what that template did with each root: the root's models, the design's pass
    (the page's design given to every component without its own, isolated=False: the page
    loads the design's style sheets once), its hooks kept for components added later (a scene
    built when first visited), Panel's preprocessing and its clean-up when the session ends.
    The page has no busy spinner (Panel's reflects the whole server process: every slider
    move in any session turned it on and off in every open page, two patches to each of N
    pages a move; a page says itself that its own change is pending, scene.PENDING_JS), no
    script area, no modal and no report of the browser (app/static/classroom.html).
    """

    design = PAGE_DESIGN

    def __init__(self, sidebar: pn.viewable.Viewable, main: object, presentation: bool = False):
        self.sidebar = sidebar
        self.main = pn.panel(main)
        self.presentation = presentation

    def roots(self) -> dict[str, pn.viewable.Viewable]:
        """The page's areas by the tag the template places them with."""
        return {"main": self.main, "nav": self.sidebar}

    def servable(self, title: str = TITLE) -> ClassroomPage:
        """Into the current session's document (as Panel's ``servable``), if there is one."""
        document = pn.state.curdoc
        if document is not None and document.session_context is not None:
            self.server_doc(document, title)
        return self

    def server_doc(self, document: Document | None = None, title: str = TITLE) -> Document:
        """The page's roots, template and variables put into ``document``."""
        shell = page_shell(self.presentation, state.rel_path or "", use_cdn())
        design = shell._design
        document = init_doc(document)
        document.title = title
        document.on_session_destroyed(state._destroy_session)
        self.sidebar._add_location(document, True)
        stylesheets = {}
        cache = state._stylesheets.setdefault(document, {})
        with set_curdoc(document):  # (the served session's own document: as its script runs)
            # the page's design for its components made from now on in the session (as Panel's
            # templates do; once for the session, not a config.set around each root: 1.1 ms)
            pn.config.design = PAGE_DESIGN
            for tag, viewable in self.roots().items():
                model = viewable.get_root(document, preprocess=False)
                model.name = f"{tag}-{id(viewable)}"
                model.tags = [*model.tags, tag]
                viewable._documents[document] = model
                # (Panel's add_to_doc first walks every model of the root to take it out of
                # any other document: 4 ms of a page; this page's models are new, made for it)
                document.add_root(model)
                document.on_session_destroyed(viewable._server_destroy)
                # (Design.apply, given the document: the root is not in it until the caller's
                # freeze ends, and Design.apply then cached the style sheets process-wide,
                # where a closed page's emptied ones met the next page, and pointed them at
                # Panel's CDN, not where the server serves them, its dist_url: app/main.py)
                design._reapply(viewable, model, isolated=False, cache=cache, document=document)
                viewable._preprocess(model)
                viewable._hooks.append(design._apply_hooks)  # (components added later)
                stylesheets.update(_style_sheet_files(viewable))
        document.template = shell.template
        variables = document._template_variables
        variables.update(shell._render_variables)
        variables["template_resources"] = shell.resolve_resources(extras={"css": stylesheets})
        return document


def _style_sheet_files(viewable: pn.viewable.Viewable) -> dict[str, str]:
    """The CSS files of the components' own style sheets, which the page loads (as Panel's
    templates do)."""
    files = {}
    for component in viewable.select(pn.viewable.Viewable):
        for sheet in getattr(component, "_stylesheets", []):
            sheet = str(sheet)
            if sheet.endswith(".css"):
                files[f"extra_{os.path.basename(sheet)}"] = sheet
    return files


class _ClassroomTemplate(pn.template.BootstrapTemplate):
    """Panel's BootstrapTemplate as :func:`page_shell` keeps it: its page without a script area,
    a modal's actions or the browser's report (app/static/classroom.html)."""

    _template = Path(__file__).parent / "static" / "classroom.html"

    def __init__(self, **params):
        super().__init__(busy_indicator=None, **params)
        # (Panel adds them for every template with a state_roots block; the report of the
        # browser, the first session's, would be kept for the process's life)
        for unused in ("js_area", "actions", "browser_info"):
            self._render_items.pop(unused, None)
        self._render_variables["browser_info"] = False
