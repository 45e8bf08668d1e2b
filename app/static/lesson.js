// The lesson's card follows the class (app/lesson.py): after Start, Next or Previous the card
// shows the new step from its title; after a reveal, the answer and the buttons below it. A
// long answer had pushed the card on, and the next step opened scrolled to its last choice
// (a phone, a laptop) or with its buttons below the screen (a projector). The card is redrawn
// by the server, so this waits for it. On a projector the buttons lie above the answer: the
// card then shows from the step's title. On a phone the answer stands above the scene: the page
// shows it from its top, the scene's plot after it.
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
  // The first match shown (a phone shows the answer above the scene, a wider screen the
  // card's: both are in the page, one hidden by its width, app/lesson.py)
  const findShown = (root, selector) => {
    for (const el of root.querySelectorAll("*")) {
      if (el.matches(selector) && el.checkVisibility()) return el;
      if (el.shadowRoot) {
        const inner = findShown(el.shadowRoot, selector);
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
  // A pane's text (Panel's panes draw it in their shadow root)
  const text = (el) => (el ? (el.shadowRoot || el).textContent : null);
  // Until the user scrolls or touches the page: [a function saying so, one ending the watch]
  const watchUser = () => {
    let moved = false;
    const mark = () => { moved = true; };
    const events = ["wheel", "touchstart", "keydown", "mousedown"];
    for (const name of events) window.addEventListener(name, mark, {once: true, passive: true});
    return [() => moved, () => { for (const name of events) window.removeEventListener(name, mark); }];
  };
  // After Start, Next or Previous: the new step's title, from its top, below the header. It
  // comes from the server, and the page changes around it: after a reveal on a phone the page
  // is long (the scene, its plots drawn), and the next step's, covered, is short. Scrolled at a
  // fixed 300 ms, before a busy server's answer, the page then shrank under the window and left
  // the title and the question above the screen (a teacher's trial). So this waits for the new
  // title (a text other than the one shown at the click) and places it again while it moves,
  // for 2.5 s or until the user scrolls or touches the page.
  let stepping = 0; // the current step change's number: a new one ends the last one's watch
  window.twoballShowStep = () => {
    const mine = ++stepping;
    const started = performance.now();
    const before = text(findShown(document, ".twoball-step-title"));
    const [userMoved, stop] = watchUser();
    let placedAt = null;
    let placedTop = null;
    const tick = () => {
      if (mine !== stepping || userMoved()) return stop();
      const now = performance.now();
      const title = findShown(document, ".twoball-step-title");
      const drawn = title && title.getBoundingClientRect().height > 0 && text(title) !== before;
      if (!drawn && placedAt === null) {
        if (now - started < 15000) setTimeout(tick, 100);
        else stop();
        return;
      }
      const top = title ? title.getBoundingClientRect().top : null;
      if (top !== null && (placedTop === null || Math.abs(top - placedTop) > 1)) {
        title.style.scrollMarginTop = `${header() + 8}px`;
        title.scrollIntoView({block: "start", inline: "nearest", behavior: "instant"});
        placedTop = title.getBoundingClientRect().top;
        if (placedAt === null) placedAt = now;
      }
      if (now - placedAt < 2500) setTimeout(tick, 150);
      else stop();
    };
    setTimeout(tick, 100);
  };
  // After a reveal: the answer and the buttons below it, or, if both do not fit, the answer
  // from its top. The answer comes from the server, with the uncovered scene above it (on a
  // phone, the card lies below the scene): a busy server sent them after a fixed wait, and the
  // answer was left below the screen. So this waits for the answer to be drawn, and places it
  // again while the scene above grows (its plots are drawn later), for 4 s or until the user
  // scrolls or touches the page.
  let showing = 0; // the current reveal's number: a new one ends the last one's watch
  window.twoballShowAnswer = () => {
    const mine = ++showing;
    const started = performance.now();
    let placedAt = null; // when the answer was first placed
    let placedTop = null; // its top then, after the scroll
    const [userMoved, stop] = watchUser();
    const tick = () => {
      if (mine !== showing || userMoved()) return stop();
      const now = performance.now();
      const answer = findShown(document, ".twoball-answer");
      const buttons = find(document, ".twoball-step-buttons");
      const drawn = answer && buttons && answer.getBoundingClientRect().height > 0;
      if (!drawn) {
        if (now - started < 15000) setTimeout(tick, 100);
        else stop();
        return;
      }
      const top = answer.getBoundingClientRect().top;
      if (placedTop === null || Math.abs(top - placedTop) > 1) {
        const margin = header() + 8;
        // A projector's card puts the buttons above the answer (app/lesson.py): it shows the
        // step's title and the buttons below it, the answer's end left below the screen.
        const title = find(document, ".twoball-step-title");
        const above = buttons.getBoundingClientRect().top < top;
        // A phone's answer stands above the scene it talks about (app/lesson.py): from its
        // top, the scene's plot following it; the card's buttons come after the scene.
        if (answer.classList.contains("twoball-answer-above")) {
          answer.style.scrollMarginTop = `${margin}px`;
          answer.scrollIntoView({block: "start", inline: "nearest", behavior: "instant"});
        } else if (above && title) {
          title.style.scrollMarginTop = `${margin}px`;
          title.scrollIntoView({block: "start", inline: "nearest", behavior: "instant"});
        } else {
          buttons.scrollIntoView({block: "end", inline: "nearest", behavior: "instant"});
        }
        if (!above && answer.getBoundingClientRect().top < margin) {
          answer.style.scrollMarginTop = `${margin}px`;
          answer.scrollIntoView({block: "start", inline: "nearest", behavior: "instant"});
        }
        placedTop = answer.getBoundingClientRect().top;
        if (placedAt === null) placedAt = now;
      }
      if (now - placedAt < 4000) setTimeout(tick, 150);
      else stop();
    };
    setTimeout(tick, 300);
  };
  // On a phone the lesson's card lies under the scene and the controls (its Start at y 1563 of
  // a 2226 px page, a teacher's trial): while it offers Start, a button at the top of the page
  // offers it too, and presses it. A plain button in the template's own page, outside Bokeh's
  // models: a page opened without the lesson (most of a class's) costs the server nothing more.
  const PHONE_START = "Start the six-step lesson";
  const narrow = window.matchMedia("(max-width: 767px)");
  const startButton = (root) => {
    for (const el of root.querySelectorAll("*")) {
      if (el.tagName === "BUTTON" && el.textContent.trim() === "Start the lesson" &&
          el.checkVisibility()) return el;
      if (el.shadowRoot) {
        const inner = startButton(el.shadowRoot);
        if (inner) return inner;
      }
    }
    return null;
  };
  let phoneStart = null;
  const offerStart = () => {
    const main = document.querySelector("#main");
    if (!main || !window.Bokeh) return;
    if (!phoneStart) {
      phoneStart = document.createElement("button");
      phoneStart.type = "button";
      phoneStart.className = "btn btn-primary twoball-phone-start";
      phoneStart.textContent = PHONE_START;
      phoneStart.style.margin = "8px 10px";
      phoneStart.hidden = true;
      phoneStart.addEventListener("click", () => {
        const start = startButton(document);
        phoneStart.hidden = true;
        if (start) start.click();
      });
      main.prepend(phoneStart);
    }
    phoneStart.hidden = !(narrow.matches && startButton(document));
  };
  setInterval(offerStart, 700);
})();
