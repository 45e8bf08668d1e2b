// The animations of the drop and Stack scenes, drawn in the page (app/animation.py): a scene's
// frames source calls twoballDrawFrame when its frames arrive, and the player when its frame
// changes. Kept here, loaded once and cached, rather than sent in every page's document.
(() => {
  // Panel's player sends its frame number to the server at every frame (about 1.5 ms of server
  // CPU each, 37 ms a second for each student playing). Once a page has a drop's frames, a
  // playing player's frames stay in the page (setv without sync; the callbacks that draw still
  // run), and the server hears where it stopped (value_throttled, at the pause or the last
  // frame). Play at the last frame starts again from the first (Panel's did nothing there,
  // which a teacher took for a broken player). Where Panel's player lacks what this replaces
  // (a later Panel), the player syncs as before.
  const installLocalPlay = (view) => {
    if (view.twoball_local_play || !view.set_frame || !view.pause_animation
        || !view.play_animation || !view.update_title_and_value) return;
    const set_frame = view.set_frame, pause_animation = view.pause_animation;
    const play_animation = view.play_animation;
    view.play_animation = function () {  // from the start again when at the end
      if (this.model.value >= this.model.end) this.set_frame(this.model.start);
      play_animation.call(this);
    };
    view.set_frame = function (frame, throttled = true) {
      const frames = this.model.twoball_frames;
      if (this.timer == null || frames == null || frames.data.t.length == 0)
        return set_frame.call(this, frame, throttled);
      this.model.setv({value: frame}, {sync: false});
      this.update_title_and_value();
      if (this.sliderEl.value != String(frame)) this.sliderEl.value = String(frame);
    };
    view.pause_animation = function () {
      pause_animation.call(this);
      if (this.model.value_throttled !== this.model.value)
        this.model.value_throttled = this.model.value;
    };
    view.twoball_local_play = true;
  };

  // frames, balls (the drawn balls' source: its radii and colours stay, its centres change),
  // cursor (a Span), title (the stage's Title), unit (of time, in the caption), trail (a
  // source, or null) and trail_lines (its renderers), player (the Player's model, once made)
  window.twoballDrawFrame = ({frames, balls, cursor, title, unit, trail, trail_lines, player}) => {
    if (player != null) {
      player.twoball_frames = frames;
      installLocalPlay(player.default_view.prototype);
    }
    const data = frames.data;
    const frame_count = data.t.length;
    if (frame_count == 0 || player == null) return;
    const at = Math.max(0, Math.min(player.value, frame_count - 1));
    const drawn = balls.data;
    balls.setv({data: {...drawn, y: drawn.r.map((_, b) => data["y" + b][at])}}, {sync: false});
    cursor.setv({location: data.t[at]}, {sync: false});
    const time = String(Number(data.t[at].toPrecision(4)));  // as time_caption writes it
    title.setv({text: `t = ${time} ${unit}` + (data.slow[at] ? " (slow)" : "")}, {sync: false});
    if (trail != null && trail_lines.length > 0 && trail_lines[0].visible) {
      const shown = {t: Array.from(data.t.slice(0, at + 1))};
      drawn.r.forEach((radius, b) => {
        const centres = data["y" + b];
        shown["top" + b] = shown.t.map((_, i) => centres[i] + radius);
      });
      trail.setv({data: shown}, {sync: false});
    }
  };
})();
