// The dashboard's shell: log in with an API key, then route #/jobs, #/job/ID, #/sweeps,
// #/sweep/ID, #/robots, #/robot/ID to their pages. Every page returns a cleanup function
// (stops its polling) that runs when the user navigates away.
import { api, ApiError, clearKey, getKey, setKey, whenUnauthorized } from "./api.js";
import { clear, errorBox, errorText, h } from "./ui.js";
import * as jobs from "./pages/jobs.js";
import * as job from "./pages/job.js";
import * as sweeps from "./pages/sweeps.js";
import * as sweep from "./pages/sweep.js";
import * as robots from "./pages/robots.js";

/** @typedef {import("./api_types").UsageOut} UsageOut */
/**
 * A page: render(main, the route's parameter, the whole hash) draws it into `main` and may
 * answer a cleanup function (stops its polling).
 * @typedef {{ render(main: HTMLElement, param: string, hash: string): Promise<(() => void) | void> }} Page
 */

/** @type {Array<[RegExp, Page, string]>} hash pattern, page, the nav link to mark */
const ROUTES = [
  [/^#\/jobs(?:\?(.*))?$/, jobs, "jobs"],
  [/^#\/job\/([\w-]+)$/, job, "jobs"],
  [/^#\/sweeps$/, sweeps, "sweeps"],
  [/^#\/sweep\/([\w-]+)$/, sweep, "sweeps"],
  [/^#\/robots$/, robots, "robots"],
  [/^#\/robot\/([\w.-]+)$/, robots, "robots"],
];

const main = /** @type {HTMLElement} */ (document.getElementById("app"));
/** @type {(() => void) | null} */
let cleanup = null;
/** @param {string} id an element of index.html */
const byId = (id) => /** @type {HTMLElement} */ (document.getElementById(id));

async function route() {
  if (cleanup) { try { cleanup(); } catch (_) { /* page gone */ } cleanup = null; }
  if (!getKey()) { showLogin(); return; }
  const hash = location.hash || "#/jobs";
  for (const [re, page, nav] of ROUTES) {
    const m = re.exec(hash);
    if (!m) continue;
    for (const a of /** @type {NodeListOf<HTMLElement>} */ (document.querySelectorAll("[data-nav]"))) {
      a.classList.toggle("active", a.dataset.nav === nav);
    }
    clear(main);
    try {
      cleanup = (await page.render(main, m[1] || "", hash)) || null;
    } catch (err) {
      main.append(errorBox(err));
    }
    return;
  }
  location.hash = "#/jobs";
}

function showLogin(message = "") {
  const dialog = /** @type {HTMLDialogElement} */ (byId("login"));
  byId("login-error").textContent = message;
  byId("who").textContent = "";
  byId("logout").hidden = true;
  clear(main).append(h("p.muted", "Log in with your API key to see your jobs."));
  if (!dialog.open) dialog.showModal();
}

/** @param {string} key */
async function login(key) {
  setKey(key);
  try {
    /** @type {UsageOut} */
    const me = await api("/keys/me");
    /** @type {HTMLDialogElement} */ (byId("login")).close();
    showWho(me);
    await route();
  } catch (err) {
    clearKey();
    showLogin(err instanceof ApiError && err.status === 401 ? "This key is not valid." : errorText(err));
  }
}

/** @param {UsageOut} me */
function showWho(me) {
  /** @type {Partial<UsageOut["key"]>} */
  const k = me.key || {};
  byId("who").textContent = `${k.name || "key"} (${k.role || "user"})`;
  byId("logout").hidden = false;
}

byId("login-form").addEventListener("submit", (ev) => {
  ev.preventDefault();
  login(/** @type {HTMLInputElement} */ (byId("login-key")).value.trim());
});
byId("login").addEventListener("cancel", (ev) => ev.preventDefault());
byId("logout").addEventListener("click", () => {
  clearKey();
  showLogin();
});
whenUnauthorized((detail) => { clearKey(); showLogin(String(detail)); });
window.addEventListener("hashchange", route);

(async () => {
  if (getKey()) {
    try { showWho(await api("/keys/me")); } catch (_) { return; /* 401 → login shown */ }
  }
  await route();
})();
