// A presentation clicker drives the lesson without a mouse. Clickers send PageDown and PageUp
// (some the right and left arrows): forward reveals the answer while it can be revealed (in
// presentation mode at once, elsewhere once a prediction is chosen), else goes to the next
// step (the last step stays: ending the lesson takes its button); back goes to the previous
// step. Forward never skips an answer still waiting for a prediction (away from a projector,
// Reveal reads "Choose an answer first"): it puts the focus on the choices instead (a new
// user's PageDown went from step 1 to 3 on a laptop and never saw an answer). Only while
// the lesson runs (its buttons are on the page), and never where the key belongs to the field
// that has the focus: any key in a text field, an arrow on a slider, a radio choice or a list.
(() => {
  // (not "End the lesson": one press too many on the last step lost the lesson)
  const FORWARD = ["Reveal the answer", "Next >"];
  const BACK = ["< Previous"];
  const WAITING = "Choose an answer first"; // (app/lesson.py CHOOSE_FIRST)
  const KEYS = {PageDown: FORWARD, ArrowRight: FORWARD, PageUp: BACK, ArrowLeft: BACK};
  const TEXT = /^(text|number|search|email|url|tel|password)$/;
  // the elements that ``wanted`` picks, in the page and every shadow root within it
  const elements = (wanted, root = document, found = []) => {
    for (const el of root.querySelectorAll("*")) {
      if (wanted(el)) found.push(el);
      if (el.shadowRoot) elements(wanted, el.shadowRoot, found);
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
    const visible = elements((el) => el.tagName === "BUTTON" && el.checkVisibility());
    if (labels === FORWARD && visible.some((b) => b.textContent.trim() === WAITING)) {
      event.preventDefault();
      const radio = (el) => el.tagName === "INPUT" && el.type === "radio" && el.checkVisibility();
      const choice = elements(radio)[0];
      if (choice) choice.focus();
      return;
    }
    const shown = visible.filter((b) => !b.disabled);
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
