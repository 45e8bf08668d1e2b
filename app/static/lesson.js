// The lesson's card follows the class (app/lesson.py): after Start, Next or Previous the card
// shows the new step from its title; after a reveal, the answer and the buttons below it. A
// long answer had pushed the card on, and the next step opened scrolled to its last choice
// (a phone, a laptop) or with its buttons below the screen (a projector). The card is redrawn
// by the server, so this waits a moment for it.
(() => {
  const find = (root, selector) => {
    const hit = root.querySelector(selector);
    if (hit) return hit;
    for (const el of root.querySelectorAll("*")) {
      if (el.shadowRoot) {
        const inner = find(el.shadowRoot, selector);
        if (inner) return inner;
      }
    }
    return null;
  };
  // A phone's page scrolls under the template's header, which stays on top (sticky): a title
  // scrolled to the top of the window was hidden behind it, so it stops below the header.
  const header = () => {
    const el = document.querySelector("#header");
    const stays = el && ["sticky", "fixed"].includes(getComputedStyle(el).position);
    return stays ? el.getBoundingClientRect().height : 0;
  };
  const show = (selector, block) => setTimeout(() => {
    const el = find(document, selector);
    if (!el) return;
    el.style.scrollMarginTop = `${header() + 8}px`;
    el.scrollIntoView({block, inline: "nearest", behavior: "instant"});
  }, 300);
  window.twoballShowStep = () => show(".twoball-step-title", "start");
  window.twoballShowAnswer = () => show(".twoball-step-buttons", "end");
})();
