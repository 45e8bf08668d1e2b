// What the widgets do not say to a screen reader or show to a keyboard, added in the browser
// (Bokeh and Panel render them in shadow roots the app's CSS does not reach):
// - a slider handle is named by its title ("mu = m2/m1 (log scale)"), and its value reads as
//   the title shows it (0.01), not as the handle's own number (a log slider's exponent, -2.00);
// - the animation player's buttons and frame slider, and each checkbox, get names;
// - a keyboard focus is drawn as a thick orange ring, visible on a projector;
// - the template's sidebar list (<ul> holding no <li>) is presented as what it is, a group;
// - two things Bokeh makes focusable (tabindex 0) had no name: each plot's event layer, which
//   the keyboard reaches, is a group named by the plot's title (or its axis), and a toolbar's
//   overflow (its "⋯") a button named "more plot tools";
// - the scenes' tabs are a tab list, the one on screen selected.
// New widgets appear as scenes are first visited: every second the page is looked over again,
// and a handle's value is mended as soon as the slider changes it.
(() => {
  const PLAYER = {
    slower: "slower", first: "first frame", previous: "previous frame",
    reverse: "play backwards", pause: "pause", play: "play", next: "next frame",
    last: "last frame", faster: "faster",
  };
  const ring = new CSSStyleSheet();
  ring.replaceSync(
    ":focus-visible { outline: 3px solid #E69F00 !important; outline-offset: 2px !important; }"
  );
  const seen = new WeakSet();
  const set = (el, name, value) => {
    if (value && el.getAttribute(name) !== value) el.setAttribute(name, value);
  };
  const shadowRoots = (root, found) => {
    for (const el of root.querySelectorAll("*")) {
      if (el.shadowRoot) {
        found.push(el.shadowRoot);
        shadowRoots(el.shadowRoot, found);
      }
    }
    return found;
  };
  const nameSlider = (handle) => {
    const title = handle.getRootNode().querySelector(".bk-slider-title");
    if (!title) return;
    const shown = title.querySelector(".bk-slider-value");
    const value = shown ? shown.textContent.trim() : "";
    set(handle, "aria-label", title.textContent.replace(value, "").replace(/:\s*$/, "").trim());
    set(handle, "aria-valuetext", value);
  };
  const watchSlider = (handle) => {
    nameSlider(handle);
    const mend = () => nameSlider(handle);
    new MutationObserver(mend).observe(handle, {attributeFilter: ["aria-valuetext"]});
    const title = handle.getRootNode().querySelector(".bk-slider-title");
    if (title) {
      new MutationObserver(mend).observe(title, {subtree: true, childList: true, characterData: true});
    }
  };
  const mendAll = () => {
    for (const root of shadowRoots(document, [])) {
      if (!seen.has(root)) {
        seen.add(root);
        root.adoptedStyleSheets = [...root.adoptedStyleSheets, ring];
      }
      for (const handle of root.querySelectorAll(".noUi-handle")) {
        if (!seen.has(handle)) {
          seen.add(handle);
          watchSlider(handle);
        }
      }
      for (const [cls, name] of Object.entries(PLAYER)) {
        for (const button of root.querySelectorAll(`button.${cls}`)) set(button, "aria-label", name);
      }
      for (const frame of root.querySelectorAll('input[type="range"]')) {
        set(frame, "aria-label", "animation frame");
      }
      // the scenes' tabs, named as such (Bokeh draws them as plain focusable divs)
      for (const list of root.querySelectorAll(".bk-headers-wrapper")) set(list, "role", "tablist");
      for (const tab of root.querySelectorAll(".bk-headers-wrapper > .bk-tab")) {
        set(tab, "role", "tab");
        set(tab, "aria-selected", String(tab.classList.contains("bk-active")));
      }
      for (const box of root.querySelectorAll('input[type="checkbox"]')) {
        const label = (box.parentElement ?? root).querySelector(".bk-label, span");
        if (label) set(box, "aria-label", label.textContent.trim());
      }
    }
    for (const list of document.querySelectorAll("ul.nav")) set(list, "role", "presentation");
    for (const root of shadowRoots(document, [])) {
      for (const more of root.querySelectorAll(".bk-tool-overflow")) {
        set(more, "role", "button");
        set(more, "aria-label", "more plot tools");
      }
    }
    for (const view of window.Bokeh ? Bokeh.index.all_views() : []) {
      const events = view.canvas_view && view.canvas_view.events_el;
      if (!events || !("title" in view.model)) continue;
      const title = view.model.title && view.model.title.text;
      const axis = (view.model.left || [])[0];
      const about = title || (axis && axis.axis_label) || "";
      set(events, "role", "group");  // (it holds the toolbar: an image may not)
      set(events, "aria-label", about ? `plot: ${about}` : "plot");
    }
  };
  document.adoptedStyleSheets = [...document.adoptedStyleSheets, ring];
  setInterval(mendAll, 1000);
  window.addEventListener("load", mendAll);
})();
