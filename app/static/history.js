// The explorer writes its state into the URL with history.pushState (Panel's Location), but
// nothing tells the server when the browser goes Back or Forward: the URL would change and the
// page would not. Reload instead, so that the page is built again from the URL it now shows.
window.addEventListener("popstate", () => window.location.reload());
