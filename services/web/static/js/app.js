// The dashboard's shell: log in with an API key, then route #/jobs, #/job/ID, #/sweeps,
// #/sweep/ID, #/robots, #/robot/ID to their pages. Every page returns a cleanup function
// (stops its polling) that runs when the user navigates away.
import { api, clearKey, getKey, setKey, whenUnauthorized } from "./api.js";
import { clear, errorBox, h } from "./ui.js";
import * as jobs from "./pages/jobs.js";
import * as job from "./pages/job.js";
import * as sweeps from "./pages/sweeps.js";
import * as sweep from "./pages/sweep.js";
import * as robots from "./pages/robots.js";

const ROUTES = [
  [/^#\/jobs(?:\?(.*))?$/, jobs, "jobs"],
  [/^#\/job\/([\w-]+)$/, job, "jobs"],
  [/^#\/sweeps$/, sweeps, "sweeps"],
  [/^#\/sweep\/([\w-]+)$/, sweep, "sweeps"],
  [/^#\/robots$/, robots, "robots"],
  [/^#\/robot\/([\w.-]+)$/, robots, "robots"],
];

const main = document.getElementById("app");
let cleanup = null;

async function route() {
  if (cleanup) { try { cleanup(); } catch (_) { /* page gone */ } cleanup = null; }
  if (!getKey()) { showLogin(); return; }
  const hash = location.hash || "#/jobs";
  for (const [re, page, nav] of ROUTES) {
    const m = re.exec(hash);
    if (!m) continue;
    for (const a of document.querySelectorAll("[data-nav]")) {
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
  const dialog = document.getElementById("login");
  document.getElementById("login-error").textContent = message;
  document.getElementById("who").textContent = "";
  document.getElementById("logout").hidden = true;
  clear(main).append(h("p.muted", "Log in with your API key to see your jobs."));
  if (!dialog.open) dialog.showModal();
}

async function login(key) {
  setKey(key);
  try {
    const me = await api("/keys/me");
    document.getElementById("login").close();
    showWho(me);
    await route();
  } catch (err) {
    clearKey();
    showLogin(err.status === 401 ? "This key is not valid." : err.message);
  }
}

function showWho(me) {
  const k = me.key || {};
  document.getElementById("who").textContent = `${k.name || "key"} (${k.role || "user"})`;
  document.getElementById("logout").hidden = false;
}

document.getElementById("login-form").addEventListener("submit", (ev) => {
  ev.preventDefault();
  login(document.getElementById("login-key").value.trim());
});
document.getElementById("login").addEventListener("cancel", (ev) => ev.preventDefault());
document.getElementById("logout").addEventListener("click", () => {
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
