// The job page's metrics card: the metrics of the reported optimum beside the paper's printed
// start → optimum (examples/papers/paper_numbers.yaml: only for a job on the paper's robot with
// the paper's settings) and each baseline's (marked infeasible when it violates a constraint on
// this robot), and what the optimiser earned over its initial population and the no-search
// solution.
import { fill, h, num, violationText } from "../ui.js";

/** @typedef {import("../api_types").EarnedStart} EarnedStart */
/** @typedef {import("../api_types").FrontOut} FrontOut */
/** @typedef {import("../api_types").ResultOut} ResultOut */

/**
 * The metrics of the reported optimum into `metrics`: each with its readable name and unit, the
 * paper's printed start → optimum where it applies, and each baseline's value.
 * @param {HTMLElement} metrics
 * @param {FrontOut} front
 * @param {ResultOut} result
 */
export function drawMetrics(metrics, front, result) {
  const labels = Object.fromEntries(front.metrics.map((q) => [q.name, q]));
  const paper = front.paper ? front.paper.metrics : null;
  /** @param {string} k */
  const paperCell = (k) => {
    const pv = paper && paper[k];
    if (!pv) return h("td.num.muted", "—");
    const text = `${pv.start === null ? "" : `${num(pv.start)} → `}${num(pv.optimum)}`;
    return h("td.num", { title: [pv.symbol && `paper: ${pv.symbol}`, pv.note].filter(Boolean).join(" — ") }, text);
  };
  const rows = Object.entries(result.metrics || {}).map(([k, v]) => {
    const q = labels[k] || { label: k, unit: "" };
    return h("tr", h("td", q.label), h("td.mono.muted", k), h("td.num", num(v)), h("td", q.unit),
      paper ? paperCell(k) : null, front.baselines.map((b) => h("td.num", num(b.metrics[k]))));
  });
  fill(metrics, earnedBlock(result), h("h2", "Metrics of the reported optimum"),
    h("table#metrics-table", h("thead", h("tr", h("th", "metric"), h("th", "name"), h("th.num", "optimum"), h("th", "unit"),
      paper ? h("th.num", { title: front.paper?.source }, "paper: start → optimum") : null,
      front.baselines.map((b) => baselineHead(b.name, result)))), h("tbody", rows)));
}

// A baseline's column: its name, and "infeasible" in red when it violates a constraint on
// this robot (a change against it would mean nothing).
/**
 * @param {string} name
 * @param {ResultOut} result
 */
function baselineHead(name, result) {
  const rec = (result.baselines || []).find((x) => x.name === name);
  if (!rec || rec.feasible !== false) return h("th.num", `baseline ${name}`);
  return h("th.num", { title: rec.violations.map(violationText).join("; ") }, `baseline ${name} `,
    h("span.error", "(infeasible)"));
}

// What the optimiser earned: its initial population's best and the solution the encoding
// gives with no search (summary.start, legcore/earned.py) beside the optimum.
/** @param {ResultOut} result */
function earnedBlock(result) {
  /** @type {EarnedStart | null | undefined} */
  const st = result.summary?.start;
  if (!st || !st.objectives) return null;
  const rows = st.objectives.map((r) => h("tr", h("td.mono", r.objective), h("td.num", num(r.initial)),
    h("td.num", num(r.free)), h("td.num", num(r.optimum)), h("td.num", r.earned_pct == null ? "" : `${num(r.earned_pct)} %`)));
  return h("section#earned", h("h2", "What the optimiser earned"), h("p", st.verdict),
    h("table", h("thead", h("tr", h("th", "objective (minimised)"), h("th.num", "initial population's best"),
      h("th.num", st.free ? `${st.free.what} (no search)` : "no-search solution"), h("th.num", "optimum"),
      h("th.num", "earned over the initial best"))), h("tbody", rows)));
}
