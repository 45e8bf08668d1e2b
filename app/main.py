"""``panel serve app``: one Explorer per browser session, its state read from the URL."""

from contextlib import nullcontext

import panel as pn
from panel.io.resources import get_dist_path

from .explorer import Explorer
from .scene import send_without_delay

# app/static/ (Bokeh serves it): history.js, Back and Forward rebuild the page from the URL they
# go to (the URL follows the state; nothing told the server when it went back); keys.js, a
# presentation clicker's keys drive the lesson; a11y.js, names and a focus ring the widgets lack;
# drag.js, a slider's drag stays in the page until its release; animation.js, the animations
# drawn in the page (app/animation.py); pending.js, a page waiting for its change's answer
# (app/scene.py); lesson.js, the lesson's card scrolled to each new step; projector.js, the
# header's link to the projector view and back
pn.extension(
    notifications=False,
    # (the browser's report: only Panel's chat reads it; switched off here, for each session:
    # a module-level pn.config.browser_info = False, set while the first page imports the app,
    # was kept by Panel for that session alone, and that first page never connected)
    browser_info=False,
    js_files={
        "history": "app/static/history.js",
        "keys": "app/static/keys.js",
        "a11y": "app/static/a11y.js",
        "drag": "app/static/drag.js",
        "animation": "app/static/animation.js",
        "pending": "app/static/pending.js",
        "lesson": "app/static/lesson.js",
        "projector": "app/static/projector.js",
    },
)

# Panel's models name their style sheets on its CDN unless the document says where the server
# serves them, which Panel writes only while it renders a session's page. A session built when
# its websocket connects (twoball serve reuses the first page's HTML: app/serve.py) has no such
# render, and its pages asked cdn.holoviz.org for their CSS (this app must not reach the network).
if pn.state.curdoc is not None:
    pn.state.curdoc.template_variables.setdefault("dist_url", get_dist_path(cdn=False))

query = {key: values[-1].decode(errors="replace") for key, values in pn.state.session_args.items()}
explorer = Explorer(query)
pn.state.onload(send_without_delay)
if pn.state.location is not None:
    explorer.follow_location(pn.state.location)
# the page's roots go into the document with its model graph recomputed once, not once per
# root (about 30 ms of a session's opening: docs/performance.md, "A class at once")
frozen = pn.state.curdoc.models.freeze() if pn.state.curdoc is not None else nullcontext()
with frozen:
    explorer.page().servable()
