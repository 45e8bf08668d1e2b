// A change the server has not answered yet (app/scene.py, PENDING_JS and ANSWERED_JS): a
// slider's release marks the page until the scene's new data arrive; a change that brings no
// new data clears it after 30 s.
(() => {
  let timer = null;
  window.twoballPending = () => {
    document.body.classList.add("twoball-pending");
    clearTimeout(timer);
    timer = setTimeout(() => document.body.classList.remove("twoball-pending"), 30000);
  };
  window.twoballAnswered = () => document.body.classList.remove("twoball-pending");
})();
