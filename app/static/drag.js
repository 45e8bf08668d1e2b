// A slider's drag stays in the page until its release. Bokeh's slider sends its value to the
// server at every step of a drag (often 30-60 a second), and each costs the server about
// 1.5 ms though the explorer reads only the release (value_throttled): a class dragging
// sliders kept a core busy for nothing. Here the drag's steps change the slider in the page
// alone (its title shows each value), and the release sends the final value and
// value_throttled as before. If a later Bokeh renames what this replaces, the slider sends
// every step as before.
(() => {
  const install = () => {
    let view;
    try {
      view = window.Bokeh.Models.get("Slider").prototype.default_view.prototype;
    } catch (error) {
      return false;  // Bokeh's widgets are not loaded yet
    }
    if (view.twoball_drag || !view._slide || !view._change || !view._calc_from) return true;
    const change = view._change;
    view._slide = function (values) {
      if (this.twoball_synced === undefined) this.twoball_synced = this.model.value;
      this.model.setv({value: this._calc_from(values)}, {sync: false});
    };
    view._change = function (values) {
      if (this.twoball_synced !== undefined) {
        // back to the value the server has, without a signal, so that the release's value
        // is a change and is sent
        this.model.setv({value: this.twoball_synced}, {silent: true});
        this.twoball_synced = undefined;
      }
      change.call(this, values);
    };
    view.twoball_drag = true;
    return true;
  };
  if (!install()) {
    const timer = setInterval(() => install() && clearInterval(timer), 100);
  }
})();
