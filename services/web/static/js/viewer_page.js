// The page of the Rerun web viewer (/viewer/, the installed rerun-sdk's viewer, which the
// dashboard embeds in an iframe): hands a recording's bytes to the viewer with
// window.legoptOpen(bytes, name). A file, not an inline script: the page's
// Content-Security-Policy allows scripts of this server only (and WebAssembly).
// Loaded before /viewer/re_viewer.js: the fetch guard is in place before the viewer runs; the
// viewer boots once the document (and so re_viewer.js, which defines wasm_bindgen) is parsed.
"use strict";

// The viewer would report usage to its makers: this page calls no server but this one (the
// Content-Security-Policy refuses it too; this keeps the console quiet). What it refused is
// kept in window.legoptRefused (the browser tests read it).
const ownFetch = window.fetch.bind(window);
/** @type {string[]} */
const refused = [];
window.legoptRefused = refused;
window.fetch = (input, init) => {
  // a string, a URL or a Request (a URL has no .url: its own text is the address)
  const url = new URL(input instanceof Request ? input.url : String(input), location.href);
  if (url.origin !== location.origin) {
    refused.push(url.href);
    return Promise.resolve(new Response(null, { status: 204 }));
  }
  return ownFetch(input, init);
};

const statusLine = /** @type {HTMLElement} */ (document.getElementById("status"));
/** @type {RerunWebHandle | null} */
let handle = null;
let channel = 0;
/** @type {[ArrayBuffer | Uint8Array, string | undefined] | null} */
let queued = null;

/** @param {string} text shown in the status line (hidden when empty) */
function say(text) { statusLine.textContent = text; statusLine.hidden = !text; }

/**
 * Open a recording (ArrayBuffer or Uint8Array); replaces the previous one.
 * @param {ArrayBuffer | Uint8Array} bytes
 * @param {string} [name]
 */
window.legoptOpen = function (bytes, name) {
  if (!handle) { queued = [bytes, name]; return; }
  if (channel) handle.close_channel(`legopt-${channel}`);
  channel += 1;
  handle.open_channel(`legopt-${channel}`, name || "recording");
  handle.send_rrd_to_channel(`legopt-${channel}`, new Uint8Array(bytes));
  document.body.dataset.loaded = name || "recording";
};

async function boot() {
  const res = await fetch("/viewer/re_viewer_bg.wasm");
  if (!res.ok) throw new Error(`the viewer's wasm: HTTP ${res.status} ${await res.text()}`);
  await wasm_bindgen(res);
  const h = new wasm_bindgen.WebHandle({
    url: [], hide_welcome_screen: true, enable_history: false, persist: false,
    notebook: false, render_backend: new URLSearchParams(location.search).get("renderer"),
  });
  await h.start(document.getElementById("viewer-canvas"));
  handle = h;
  window._handle = h;
  say("");
  document.body.dataset.ready = "1";
  if (queued) { window.legoptOpen?.(...queued); queued = null; }
  if (window.parent !== window) window.parent.postMessage({ legoptViewer: "ready" }, location.origin);
  setInterval(() => {
    if (h.has_panicked()) say(`The viewer stopped: ${h.panic_message()}`);
  }, 2000);
}
document.addEventListener("DOMContentLoaded", () => boot().catch((err) => {
  say(`The viewer could not start: ${err}`);
  document.body.dataset.error = String(err);
  if (window.parent !== window) window.parent.postMessage({ legoptViewer: "error", error: String(err) }, location.origin);
}));
