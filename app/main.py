"""``panel serve app``: one Explorer per browser session, its state read from the URL."""

import panel as pn

from .explorer import Explorer

pn.extension(notifications=False)

query = {key: values[-1].decode(errors="replace") for key, values in pn.state.session_args.items()}
explorer = Explorer(query)
if pn.state.location is not None:
    explorer.follow_location(pn.state.location)
# On a phone the controls go below the plots, full width, and the menu button folds them away
NARROW_SCREEN_CSS = """
@media (max-width: 700px) {
  #content { flex-direction: column-reverse; flex-wrap: nowrap; height: auto; overflow-y: auto; }
  #sidebar { width: 100% !important; height: auto; border-right: none; }
  #main { width: 100%; height: auto; max-height: none !important; overflow: visible; padding: 6px; }
}
"""
# A template gives the page its viewport tag and a sidebar that folds away (BootstrapTemplate:
# FastListTemplate loads its font from Google, which a classroom network may not reach)
pn.template.BootstrapTemplate(
    title="Two-ball bounce explorer",
    sidebar=[explorer.sidebar()],
    main=[explorer.tabs],
    sidebar_width=330,
    header_background="#1f4e79",
    raw_css=[NARROW_SCREEN_CSS],
    meta_viewport="width=device-width, initial-scale=1",
).servable()
