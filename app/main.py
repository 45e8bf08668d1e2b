"""``panel serve app``: one Explorer per browser session, its state read from the URL."""

import panel as pn

from .explorer import Explorer
from .scene import send_without_delay

# app/static/history.js (Bokeh serves app/static/): Back and Forward rebuild the page from
# the URL they go to (the URL follows the state; nothing told the server when it went back)
pn.extension(notifications=False, js_files={"history": "app/static/history.js"})

query = {key: values[-1].decode(errors="replace") for key, values in pn.state.session_args.items()}
explorer = Explorer(query)
pn.state.onload(send_without_delay)
if pn.state.location is not None:
    explorer.follow_location(pn.state.location)
explorer.page().servable(title="Two-ball bounce explorer")
