// A link in the header between the page as it is and its projector view (?present=1: large
// text, every scene within 1280 x 720). A teacher at a projector found nothing in the page that
// offered it (it was only in the README). The link is made here, in the page, because a
// session's HTML is the same for every page (app/serve.py reuses it) and costs the server
// nothing; it reloads the page's own URL, which holds the drop, scene and step, with present
// set or removed. Hidden on a phone (PAGE_CSS), which a room does not watch.
(() => {
  const presenting = () => ["1", "true", "yes"].includes(
    new URLSearchParams(window.location.search).get("present"));
  const toggled = () => {
    const url = new URL(window.location.href);
    if (presenting()) url.searchParams.delete("present");
    else url.searchParams.set("present", "1");
    return url.href;
  };
  const place = () => {
    const items = document.getElementById("header-items");
    if (!items || document.getElementById("twoball-projector")) return;
    const link = document.createElement("a");
    link.id = "twoball-projector";
    link.textContent = presenting() ? "Leave projector view" : "Projector view";
    link.title = presenting()
      ? "Back to the page for a laptop or a tablet"
      : "Large text, every scene within a 1280 x 720 projector";
    link.href = toggled();
    // (the URL follows the sliders after the page opened: the link is made at the click)
    link.addEventListener("click", () => { link.href = toggled(); });
    link.addEventListener("focus", () => { link.href = toggled(); });
    items.appendChild(link);
  };
  if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", place);
  else place();
})();
