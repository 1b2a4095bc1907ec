// A job's parameter importance (GET /jobs/{id}/trials/importance): how much each decision
// variable explains of each objective over the stored trials — scikit-learn's random forest per
// objective, mean decrease in impurity, normalised to sum to 1 — as one horizontal bar chart
// per objective (SVG, like the parallel coordinates). The API fits on the feasible trials, or
// on every trial when fewer than 10 are feasible: the card says so then. Estimated once the job
// has finished (cached by the API); while it runs, on request.
import { api } from "../api.js";
import { errorText, fill, h, num } from "../ui.js";

/** @typedef {import("../api_types").ImportanceOut} ImportanceOut */
/** @typedef {import("../api_types").TrialPage} TrialPage */
/** @typedef {import("../api_types").Quantity} Quantity */

/** Fewer feasible trials than this: the API fits on every trial (MIN_TRIALS of services/api/importance.py). */
const MIN_FEASIBLE = 10;
/** Bars per objective; the remaining variables are summed in one "others" bar. */
const MAX_BARS = 12;
const SVG = "http://www.w3.org/2000/svg";

/**
 * An SVG element with attributes and (optionally) text.
 * @param {string} tag
 * @param {Record<string, string | number>} [attrs]
 * @param {string} [text]
 * @returns {SVGElement}
 */
function s(tag, attrs = {}, text) {
  const el = /** @type {SVGElement} */ (document.createElementNS(SVG, tag));
  for (const [k, v] of Object.entries(attrs)) el.setAttribute(k, String(v));
  if (text !== undefined) el.textContent = text;
  return el;
}

/**
 * The importance card of job `jobId`: `load()` asks the API and draws; `finished()` loads once
 * when the job has finished (the page calls it on each refresh).
 * @param {string} jobId
 * @returns {{ el: HTMLElement, load: () => Promise<void>, finished: () => void }}
 */
export function importanceCard(jobId) {
  const body = h("div#importance-body", { dataset: { state: "waiting" } },
    h("p.muted", "Estimated when the job has finished (a random forest per objective over its trials)."));
  const now = h("button.secondary#importance-now", { on: { click: () => { load(); } } }, "Estimate now");
  const el = h("div.card#importance",
    h("div.toolbar", h("h2", "Parameter importance"), h("span.spacer"), now),
    h("p.muted#importance-method-name", "random-forest impurity importance, scikit-learn: the share of each "
      + "decision variable in explaining each objective over the job's trials (they sum to 100 % per objective)."),
    body);
  let started = false;

  async function load() {
    started = true;
    body.dataset.state = "loading";
    fill(body, h("p.muted", "fitting a forest per objective…"));
    try {
      const [imp, feasible] = await Promise.all([
        /** @type {Promise<ImportanceOut>} */ (api(`/jobs/${jobId}/trials/importance`)),
        /** @type {Promise<TrialPage>} */ (api(`/jobs/${jobId}/trials?feasible=true&limit=1`)),
      ]);
      draw(imp, feasible.matched, feasible.stored);
    } catch (err) {
      body.dataset.state = "error";
      fill(body, h("p.error", errorText(err)));
    }
  }

  /**
   * @param {ImportanceOut} imp
   * @param {number} nFeasible feasible trials stored
   * @param {number} nStored trials stored
   */
  function draw(imp, nFeasible, nStored) {
    if (!imp.trials || !imp.variables.length) {
      body.dataset.state = "empty";
      fill(body, h("p.muted#importance-note", "No trials stored: there is nothing to estimate."));
      return;
    }
    const few = nFeasible < MIN_FEASIBLE;
    body.dataset.state = few ? "few-feasible" : "ok";
    fill(body,
      few ? h("p.warn#importance-note", `Not enough feasible trials: ${nFeasible} of ${nStored} `
        + `(fewer than ${MIN_FEASIBLE}). The forests were fitted on every trial, infeasible ones `
        + "included, so the importance says what moves the objectives, not what moves them among "
        + "feasible designs.") : null,
      h("div.importance-charts", imp.objectives.map((q, j) => chart(q, imp.importance[j] || [], imp.variables))),
      h("p.muted.small#importance-method", `${imp.method}.`));
  }

  /**
   * One objective's bars, largest first.
   * @param {Quantity} objective
   * @param {number[]} shares per variable
   * @param {Quantity[]} variables
   */
  function chart(objective, shares, variables) {
    const box = h("div.importance-chart", { dataset: { objective: objective.name } }, h("h3", objective.axis));
    if (!shares.some((v) => v > 0)) {
      box.dataset.flat = "true";
      box.append(h("p.muted", "Cannot be estimated: this objective does not vary over the trials "
        + "(or fewer than 2 of them are usable)."));
      return box;
    }
    const order = shares.map((v, i) => ({ v, q: variables[i] })).sort((a, b) => b.v - a.v);
    /** @type {Array<{ v: number, q: Quantity | null, label: string }>} */
    const rows = order.slice(0, MAX_BARS).map((r) => ({ ...r, label: r.q.label }));
    const rest = order.slice(MAX_BARS);
    if (rest.length) rows.push({ v: rest.reduce((t, r) => t + r.v, 0), q: null, label: `${rest.length} others` });
    const W = 380, rowH = 20, top = 4, labelW = 120, valueW = 54;
    const barW = W - labelW - valueW;
    const H = top * 2 + rowH * rows.length;
    const most = Math.max(...rows.map((r) => r.v)) || 1;
    const svg = s("svg", { viewBox: `0 0 ${W} ${H}`, width: "100%", height: H, role: "img",
      "aria-label": `importance of each variable for ${objective.axis}` });
    rows.forEach((r, k) => {
      const y = top + k * rowH;
      const g = s("g", { class: r.q ? "imp-row" : "imp-row others" });
      if (r.q) g.dataset.variable = r.q.name;
      g.dataset.share = String(r.v);
      g.append(s("title", {}, `${r.q ? r.q.axis : r.label}: ${num(100 * r.v, 3)} %`),
        s("text", { x: labelW - 6, y: y + rowH / 2 + 4, "text-anchor": "end", class: "imp-label" }, r.label),
        s("rect", { x: labelW, y: y + 3, height: rowH - 6, width: Math.max(1, (barW * r.v) / most).toFixed(1), class: "imp-bar" }),
        s("text", { x: W - 2, y: y + rowH / 2 + 4, "text-anchor": "end", class: "imp-value" }, `${num(100 * r.v, 3)} %`));
      svg.append(g);
    });
    box.append(svg);
    return box;
  }

  // a finished job's importance is loaded once (the API caches it): no button then
  function finished() {
    now.hidden = true;
    if (!started) load();
  }

  return { el, load, finished };
}
