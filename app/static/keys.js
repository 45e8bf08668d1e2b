// A presentation clicker drives the lesson without a mouse. Clickers send PageDown and PageUp
// (some the right and left arrows): forward reveals the answer while it can be revealed (in
// presentation mode at once, elsewhere once a prediction is chosen), else goes to the next
// step (the last step stays: ending the lesson takes its button); back goes to the previous
// step. Only while
// the lesson runs (its buttons are on the page), and never where the key belongs to the field
// that has the focus: any key in a text field, an arrow on a slider, a radio choice or a list.
(() => {
  // (not "End the lesson": one press too many on the last step lost the lesson)
  const FORWARD = ["Reveal the answer", "Next >"];
  const BACK = ["< Previous"];
  const KEYS = {PageDown: FORWARD, ArrowRight: FORWARD, PageUp: BACK, ArrowLeft: BACK};
  const TEXT = /^(text|number|search|email|url|tel|password)$/;
  const buttons = (root, found = []) => {
    for (const el of root.querySelectorAll("*")) {
      if (el.tagName === "BUTTON") found.push(el);
      if (el.shadowRoot) buttons(el.shadowRoot, found);
    }
    return found;
  };
  const owns = (el, key) => {
    if (!el || el === document.body) return false;
    if (el.isContentEditable || el.tagName === "TEXTAREA") return true;
    if (el.tagName === "INPUT" && TEXT.test(el.type)) return true;
    const arrows = el.tagName === "INPUT" || el.tagName === "SELECT" ||
      el.getAttribute("role") === "slider" || el.classList.contains("noUi-handle");
    return arrows && key.startsWith("Arrow");
  };
  document.addEventListener("keydown", (event) => {
    const labels = KEYS[event.key];
    if (!labels || event.altKey || event.ctrlKey || event.metaKey || event.shiftKey) return;
    if (owns(event.composedPath()[0], event.key)) return;
    const shown = buttons(document).filter((b) => b.checkVisibility() && !b.disabled);
    for (const label of labels) {
      const button = shown.find((b) => b.textContent.trim() === label);
      if (button) {
        event.preventDefault();
        button.click();
        return;
      }
    }
  });
})();
