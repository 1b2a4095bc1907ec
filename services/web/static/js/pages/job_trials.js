// A job's trials: every solution it evaluated (GET /jobs/{id}/trials), as a table to filter,
// sort and page, and as parallel coordinates of its objectives and variables (GET
// /jobs/{id}/trials/columns: one polyline per trial, drawn in SVG). Clicking a row or a line
// picks that trial: the job page shows its motion and its Rerun recording, as for a front point.
import { api } from "../api.js";
import { clear, errorText, fill, h, num } from "../ui.js";

/** @typedef {import("../api_types").TrialPage} TrialPage */
/** @typedef {import("../api_types").TrialColumns} TrialColumns */
/** @typedef {import("../api_types").Quantity} Quantity */

const PAGE = 25;
const MAX_LINES = 800;
const MAX_AXES = 14;
const SVG = "http://www.w3.org/2000/svg";

/**
 * An SVG element with attributes.
 * @param {string} tag
 * @param {Record<string, string | number>} [attrs]
 * @returns {SVGElement}
 */
function s(tag, attrs = {}) {
  const el = /** @type {SVGElement} */ (document.createElementNS(SVG, tag));
  for (const [k, v] of Object.entries(attrs)) el.setAttribute(k, String(v));
  return el;
}

/**
 * The trials card of job `jobId`; `onPick(t)` opens trial t's motion and recording.
 * @param {string} jobId
 * @param {(trial: number) => void} onPick
 * @returns {{ el: HTMLElement, refresh: () => Promise<void>, mark: (trial: number | null) => void }}
 */
export function trialsCard(jobId, onPick) {
  let offset = 0;
  /** @type {number | null} */
  let selected = null;
  const feasible = /** @type {HTMLSelectElement} */ (h("select#trial-feasible",
    h("option", { value: "" }, "all"), h("option", { value: "true" }, "feasible"), h("option", { value: "false" }, "infeasible")));
  const range = /** @type {HTMLInputElement} */ (h("input#trial-range", { type: "text", size: 18, placeholder: "f1:0:2.5 (column:low:high)" }));
  const sort = /** @type {HTMLSelectElement} */ (h("select#trial-sort", h("option", { value: "trial" }, "trial")));
  const desc = /** @type {HTMLInputElement} */ (h("input#trial-desc", { type: "checkbox" }));
  const info = h("span.muted#trial-info");
  const error = h("p.error#trial-error");
  const table = h("table#trial-table");
  const parallel = h("div#trial-parallel");
  const prev = h("button.secondary", { on: { click: () => { offset = Math.max(0, offset - PAGE); load(); } } }, "‹ prev");
  const next = h("button.secondary", { on: { click: () => { offset += PAGE; load(); } } }, "next ›");
  const apply = () => { offset = 0; load(); };
  for (const el of [feasible, sort, desc]) el.addEventListener("change", apply);
  range.addEventListener("change", apply);
  const el = h("div.card#trials",
    h("div.toolbar", h("h2", "Trials: every evaluated solution"), h("span.spacer"),
      h("label", "show ", feasible), h("label", " where ", range), h("label", " sort ", sort),
      h("label", " desc ", desc), prev, next),
    info, error, h("div.scroll", table),
    h("h3", "Parallel coordinates"), h("p.muted", "One line per trial (a sample when there are many); click a line to see its motion."),
    parallel);

  function query() {
    const q = new URLSearchParams();
    if (feasible.value) q.set("feasible", feasible.value);
    if (range.value.trim()) q.set("range", range.value.trim());
    return q;
  }

  /** @param {Quantity[]} objectives @param {Quantity[]} variables */
  function sortOptions(objectives, variables) {
    if (sort.options.length > 1) return;
    for (const [v, t] of [["generation", "generation"], ["cv", "constraint violation"]]) sort.append(h("option", { value: v }, t));
    for (const q of objectives) sort.append(h("option", { value: q.name }, q.axis));
    for (const q of variables.slice(0, 30)) sort.append(h("option", { value: q.name }, q.label));
  }

  async function load() {
    const q = query();
    q.set("sort", sort.value);
    if (desc.checked) q.set("descending", "true");
    q.set("offset", String(offset));
    q.set("limit", String(PAGE));
    try {
      // both requested at once: the table draws as soon as its page is in
      const filters = query();
      filters.set("max_rows", String(MAX_LINES));
      /** @type {Promise<TrialColumns>} */
      const columns = api(`/jobs/${jobId}/trials/columns?${filters}`);
      columns.catch(() => undefined); // awaited below; not an unhandled rejection if /trials fails first
      /** @type {TrialPage} */
      const page = await api(`/jobs/${jobId}/trials?${q}`);
      fill(error);
      sortOptions(page.objectives, page.variables);
      drawTable(page);
      const cols = await columns;
      drawParallel(cols);
    } catch (err) {
      fill(error, errorText(err));
    }
  }

  /** @param {TrialPage} page */
  function drawTable(page) {
    const nx = Math.min(page.variables.length, 8);
    const last = Math.min(page.offset + page.items.length, page.matched);
    fill(info, page.stored === 0 ? "No trials stored yet (they appear as generations finish)."
      : `${page.matched} of ${page.stored} trials match; ${page.matched ? page.offset + 1 : 0}–${last} shown`
        + (page.stored >= page.bound ? ` (at most ${page.bound} are kept per job: a sample of the generations)` : ""));
    clear(table);
    table.append(h("thead", h("tr", h("th", "trial"), h("th.num", "generation"), h("th", "feasible"),
      page.objectives.map((q) => h("th.num", q.axis)), h("th.num", "violation"),
      page.variables.slice(0, nx).map((v) => h("th.num", v.label)))));
    table.append(h("tbody", page.items.map((r) => {
      const tr = h(`tr.clickable${r.trial === selected ? ".selected" : ""}`, { dataset: { trial: r.trial } },
        h("td", String(r.trial)), h("td.num", String(r.generation)), h("td", r.feasible ? "yes" : h("span.error", "no")),
        r.objectives.map((v) => h("td.num", num(v))), h("td.num", num(r.cv)), r.x.slice(0, nx).map((v) => h("td.num", num(v))));
      tr.addEventListener("click", () => onPick(r.trial));
      return tr;
    })));
  }

  /** @param {TrialColumns} cols */
  function drawParallel(cols) {
    clear(parallel);
    if (!cols.trial.length) return;
    const axes = [
      ...cols.objectives.map((q, j) => ({ q, values: cols.objective_values[j] })),
      ...cols.variables.map((q, i) => ({ q, values: cols.x_values[i] })),
    ].slice(0, MAX_AXES);
    const W = Math.max(480, 90 * axes.length), H = 260, top = 24, bottom = 20, left = 40;
    const step = (W - 2 * left) / Math.max(1, axes.length - 1);
    const svg = s("svg", { viewBox: `0 0 ${W} ${H}`, width: "100%", height: H, role: "img" });
    svg.setAttribute("aria-label", "parallel coordinates of the trials");
    const scales = axes.map(({ values }) => {
      const finite = /** @type {number[]} */ (values.filter((v) => v !== null && Number.isFinite(v)));
      const lo = finite.length ? Math.min(...finite) : 0, hi = finite.length ? Math.max(...finite) : 1;
      /** @param {number | null} v */
      return (v) => (v === null || !Number.isFinite(v) ? null : top + (H - top - bottom) * (1 - (hi === lo ? 0.5 : (v - lo) / (hi - lo))));
    });
    cols.trial.forEach((t, k) => {
      const pts = axes.map(({ values }, a) => {
        const y = scales[a](values[k]);
        return y === null ? null : `${(left + a * step).toFixed(1)},${y.toFixed(1)}`;
      }).filter(Boolean);
      const line = s("polyline", { points: pts.join(" "), class: `pc-line ${cols.feasible[k] ? "feasible" : "infeasible"}${t === selected ? " selected" : ""}` });
      line.dataset.trial = String(t);
      line.append(s("title"));
      /** @type {SVGElement} */ (line.firstChild).textContent = `trial ${t}`;
      line.addEventListener("click", () => onPick(t));
      svg.append(line);
    });
    axes.forEach(({ q }, a) => {
      const x = left + a * step;
      svg.append(s("line", { x1: x, x2: x, y1: top, y2: H - bottom, class: "pc-axis" }));
      const label = s("text", { x, y: top - 8, "text-anchor": "middle", class: "pc-label" });
      label.textContent = q.axis;
      svg.append(label);
    });
    parallel.append(svg);
  }

  /** @param {number | null} trial */
  function mark(trial) {
    selected = trial;
    for (const x of table.querySelectorAll("tr.selected")) x.classList.remove("selected");
    for (const x of parallel.querySelectorAll(".pc-line.selected")) x.classList.remove("selected");
    if (trial === null) return;
    table.querySelector(`tr[data-trial="${trial}"]`)?.classList.add("selected");
    parallel.querySelector(`.pc-line[data-trial="${trial}"]`)?.classList.add("selected");
  }

  return { el, refresh: load, mark };
}
