// The embedded Rerun web viewer: an iframe of /viewer/ (the installed rerun-sdk's viewer) to
// which the page hands a recording's bytes, fetched with the API key.
import { apiBytes } from "./api.js";
import { errorText, h } from "./ui.js";

export class Viewer {
  constructor() {
    this.frame = /** @type {HTMLIFrameElement} */ (h("iframe.viewer", { src: "/viewer/", title: "Rerun viewer" }));
    this.note = h("p.muted", "Pick a front point: its recording opens here.");
    this.el = h("div", this.note, this.frame);
    this.token = 0;
  }

  /**
   * Fetch `path` (a .rrd of the API) and open it in the viewer as `name`.
   * @param {string} path
   * @param {string} name
   * @returns {Promise<void>}
   */
  async open(path, name) {
    const token = ++this.token;
    this.note.textContent = `Loading ${name}… (the first recording of a point is made on demand)`;
    try {
      const bytes = await apiBytes(path);
      if (token !== this.token) return;
      const win = this.frame.contentWindow;
      if (win && win.legoptOpen) win.legoptOpen(bytes, name);
      else this.frame.addEventListener("load", () => this.frame.contentWindow?.legoptOpen?.(bytes, name), { once: true });
      this.note.textContent = `${name} — ${(bytes.byteLength / 1e6).toFixed(2)} MB recording (Rerun ${"viewer"}).`;
      this.el.dataset.loaded = path;
    } catch (err) {
      if (token === this.token) this.note.textContent = `No recording: ${errorText(err)}`;
    }
  }
}
