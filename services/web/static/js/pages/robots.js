// Robots: yours and the catalog's; one robot's joints, limits, masses and the study kinds that
// accept it.
import { api, query } from "../api.js";
import { fill, h, num } from "../ui.js";

/** @typedef {import("../api_types").Page_RobotOut} RobotPage */
/** @typedef {import("../api_types").RobotView} RobotView */
/** @typedef {import("../api_types").StudyFit} StudyFit */

/**
 * The robots page (#/robots, #/robot/ID) into `main`.
 * @param {HTMLElement} main
 * @param {string} robotId the robot shown (URI-encoded; "" for none)
 * @returns {Promise<void>}
 */
export async function render(main, robotId) {
  const list = h("table#robots-table");
  const detail = h("div#robot-detail");
  main.append(h("h1", "Robots"), h("div.row", h("div.card.side", list), h("div.grow", detail)));
  /** @type {RobotPage} */
  const page = await api(`/robots${query({ include_catalog: true, limit: 1000 })}`);
  list.append(h("thead", h("tr", h("th", "name"), h("th", "source"))));
  const body = h("tbody");
  for (const r of page.items) {
    const tr = h("tr.clickable", { dataset: { robot: r.id } }, h("td", r.name), h("td", r.builtin ? "catalog" : r.source));
    tr.addEventListener("click", () => { location.hash = `#/robot/${encodeURIComponent(r.id)}`; });
    body.append(tr);
  }
  list.append(body);
  if (robotId) await show(decodeURIComponent(robotId));
  else detail.append(h("div.card", h("p.muted", "Pick a robot.")));

  /** @param {string} id */
  async function show(id) {
    for (const tr of list.querySelectorAll("tr.selected")) tr.classList.remove("selected");
    const row = list.querySelector(`tr[data-robot="${CSS.escape(id)}"]`);
    if (row) row.classList.add("selected");
    fill(detail, h("div.card", h("p.muted", "building the model…")));
    /** @type {RobotView} */
    const r = await api(`/dashboard/robots/${encodeURIComponent(id)}`);
    fill(detail, 
      h("div.card", h("h2", r.name),
        h("dl.kv", h("dt", "kind"), h("dd", r.kind), h("dt", "joints"), h("dd", String(r.nq)),
          h("dt", "mass"), h("dd", `${num(r.mass_kg)} kg`), r.legs.length ? [h("dt", "legs"), h("dd", r.legs.join(", "))] : null)),
      h("div.card", h("h2", "Joints"), h("table#joints-table",
        h("thead", h("tr", r.legs.length ? h("th", "leg") : null, h("th", "joint"), h("th.num", "lower [rad]"), h("th.num", "upper [rad]"),
          h("th.num", "max speed [rad/s]"), h("th.num", "max accel. [rad/s²]"), h("th.num", "max effort [N·m]"), h("th.num", "link mass [kg]"))),
        h("tbody", r.joints.map((j) => h("tr", r.legs.length ? h("td", j.leg) : null, h("td", j.name), h("td.num", num(j.lower)),
          h("td.num", num(j.upper)), h("td.num", num(j.velocity)), h("td.num", num(j.acceleration)), h("td.num", num(j.effort)), h("td.num", num(j.link_mass_kg))))))),
      h("div.card", h("h2", "Study kinds"), h("table#studies-table",
        h("thead", h("tr", h("th", "study"), h("th", "accepts"), h("th", "default task, or why not"))),
        h("tbody", r.studies.map((s) => h("tr", h("td", h("b", s.kind), h("div.muted", s.title)),
          h("td", s.accepts ? h("span.badge.succeeded", "yes") : h("span.badge.failed", "no")),
          h("td.wrap", fitText(s))))))));
  }
}

/** What a study fit says: the rules its default task was derived by (or the paper's preset),
 * or the field to change and why it is refused.
 * @param {StudyFit} s
 * @returns {string}
 */
function fitText(s) {
  if (!s.accepts) return `${s.field ? `${s.field}: ` : ""}${s.reason || ""}`;
  if (s.preset) return `the paper's settings (${s.preset})`;
  const rules = Object.entries(s.rules || {});
  return rules.length ? rules.map(([k, v]) => `${k}: ${v}`).join("; ") : "its defaults";
}
