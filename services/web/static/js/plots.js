// Plotly wrappers: the Pareto front (2-D, or 3-D for three objectives) with baselines, the
// paper's own values and the optimum marked, convergence (best per objective so far and hypervolume per generation), joint
// signals of one solution, and fronts of several sweep cells overlaid.
import { axis } from "./ui.js";

/** @typedef {import("./api_types").FrontOut} FrontOut */
/** @typedef {import("./api_types").GenerationOut} GenerationOut */
/** @typedef {import("./api_types").MotionOut} MotionOut */
/** @typedef {import("./api_types").Quantity} Quantity */
/** @typedef {import("./api_types").SweepFrontsOut} SweepFrontsOut */
/**
 * A solution picked on the front plot, in the front table or among the trials: a point, a
 * baseline or a stored trial.
 * @typedef {{ kind: "point", index: number } | { kind: "baseline", name: string }
 *   | { kind: "trial", index: number }} Selection
 */
/**
 * One job of a sweep cell's fronts (GET /sweeps/{id}/fronts: `cells[].jobs[]`, which the
 * API's schema leaves untyped): its final front's objective vectors.
 * @typedef {{ job_id: string, seed: unknown, points: number[][] }} CellFrontJob
 */
/** A plotly.js trace or layout (what the dashboard passes; plotly.js checks it). @typedef {Record<string, unknown>} PlotSpec */

const Plotly = window.Plotly;
const CONFIG = { responsive: true, displaylogo: false };
export const COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b",
  "#e377c2", "#17becf", "#bcbd22", "#7f7f7f"];
const LAYOUT = { margin: { l: 64, r: 16, t: 30, b: 50 }, hovermode: "closest",
  legend: { orientation: "h", y: -0.2 } };

/**
 * Free the plot in `el` (if plotly.js drew one there).
 * @param {(HTMLElement & { data?: unknown }) | null | undefined} el
 */
export function purge(el) { if (el && el.data) Plotly.purge(el); }

/**
 * Which objectives a front plot shows and whether its baselines may widen the axes.
 * @typedef {{ axes?: number[] | null, fitBaselines?: boolean }} FrontView
 */

/**
 * The range [lo, hi] of `values` padded by 6 % (null without a finite value).
 * @param {Array<number | null>} values
 * @returns {[number, number] | null}
 */
function padded(values) {
  const v = /** @type {number[]} */ (values.filter((x) => x !== null && Number.isFinite(x)));
  if (!v.length) return null;
  const lo = Math.min(...v), hi = Math.max(...v);
  const pad = (hi - lo) * 0.06 || Math.abs(hi) * 0.06 || 1;
  return [lo - pad, hi + pad];
}

/**
 * The front of `front` (GET /jobs/{id}/front) into `el`; `onPick({kind, index|name})`.
 * `view.axes`: the objectives to plot (2 or 3 indices; default the first 2 or 3);
 * `view.fitBaselines`: let the baselines and the paper's values widen the axes (default: the
 * axes fit the front, and marks outside it are off the plot).
 * @param {HTMLElement} el
 * @param {FrontOut} front
 * @param {(sel: Selection) => void} onPick called with the point or baseline clicked
 * @param {Selection | null} [selected] the one to ring
 * @param {FrontView} [view]
 */
export function frontPlot(el, front, onPick, selected = null, view = {}) {
  const m = front.objectives.length;
  const ax = view.axes && view.axes.length >= 2 ? view.axes : m >= 3 ? [0, 1, 2] : m === 2 ? [0, 1] : [0];
  const pts = front.points;
  /** @param {number} j */
  const col = (j) => pts.map((p) => p.objectives[j]);
  const text = pts.map((p) => `point ${p.index}`);
  /** @type {PlotSpec[]} */
  const traces = [];
  const three = ax.length >= 3;
  const base = three ? { type: "scatter3d" } : { type: "scatter" };
  /** @param {(j: number) => unknown[]} get the values of objective j */
  const xyz = (get) => (three ? { x: get(ax[0]), y: get(ax[1]), z: get(ax[2]) }
    : { x: get(ax[0]), y: ax.length > 1 ? get(ax[1]) : get(ax[0]).map(() => 0) });
  traces.push({ ...base, ...xyz(col), mode: "markers", name: "front", text,
    customdata: pts.map((p) => ["point", p.index]),
    marker: { size: three ? 4 : 8, color: COLORS[0], opacity: 0.85 } });
  if (front.best_index !== null && front.best_index !== undefined) {
    const b = pts.find((p) => p.index === front.best_index);
    if (b) {
      traces.push({ ...base, ...xyz((j) => [b.objectives[j]]), mode: "markers", name: "reported optimum",
        customdata: [["point", b.index]], text: [`point ${b.index} (optimum)`],
        marker: { size: three ? 7 : 14, symbol: three ? "diamond" : "star", color: "#ffb000",
          line: { color: "#333", width: 1 } } });
    }
  }
  const marks = front.baselines.filter((b) => ax.every((j) => b.objectives[j] !== null && b.objectives[j] !== undefined));
  if (marks.length) {
    traces.push({ ...base, ...xyz((j) => marks.map((b) => b.objectives[j])), mode: three ? "markers" : "markers+text",
      name: "baselines (study reference)", text: marks.map((b) => b.name), textposition: "top center",
      customdata: marks.map((b) => ["baseline", b.name]),
      marker: { size: three ? 6 : 11, symbol: three ? "square" : "diamond", color: COLORS[2] } });
  }
  const paper = (front.paper && front.paper.marks) || [];
  if (front.paper && paper.length) {
    traces.push({ ...base, ...xyz((j) => paper.map((p) => p.objectives[j])), mode: three ? "markers" : "markers+text",
      name: `the paper's values (${front.paper.source})`, text: paper.map((p) => p.label), textposition: "bottom center",
      hoverinfo: "text+x+y" + (three ? "+z" : ""),
      marker: { size: three ? 7 : 13, symbol: three ? "cross" : "x", color: "#9467bd", line: { color: "#333", width: 1 } } });
  }
  if (selected && selected.kind === "point") {
    const s = pts.find((p) => p.index === selected.index);
    if (s) {
      traces.push({ ...base, ...xyz((j) => [s.objectives[j]]), mode: "markers", name: "selected",
        customdata: [["point", s.index]], hoverinfo: "skip",
        marker: { size: three ? 9 : 18, color: "rgba(0,0,0,0)", line: { color: "#d62728", width: 3 } } });
    }
  }
  const o = front.objectives;
  // the axes fit the front unless asked to fit the baselines too (or there is no front)
  const fit = !view.fitBaselines && pts.length > 1;
  /** @param {number} i the plot axis (0 x, 1 y, 2 z) */
  const axisSpec = (i) => {
    const r = fit && ax[i] !== undefined ? padded(col(ax[i])) : null;
    return { title: { text: ax[i] !== undefined ? axis(o[ax[i]]) : "" }, ...(r ? { range: r, autorange: false } : {}) };
  };
  const layout = three
    ? { ...LAYOUT, scene: { xaxis: axisSpec(0), yaxis: axisSpec(1), zaxis: axisSpec(2) }, margin: { l: 0, r: 0, t: 20, b: 0 } }
    : { ...LAYOUT, xaxis: axisSpec(0), yaxis: ax.length > 1 ? axisSpec(1) : { title: { text: "" } } };
  Plotly.react(el, traces, layout, CONFIG);
  const plot = /** @type {PlotlyHTMLElement} */ (el);
  plot.removeAllListeners && plot.removeAllListeners("plotly_click");
  plot.on("plotly_click", (ev) => {
    const cd = /** @type {["point", number] | ["baseline", string] | undefined} */ (ev.points && ev.points[0] && ev.points[0].customdata);
    if (!cd) return;
    onPick(cd[0] === "point" ? { kind: "point", index: cd[1] } : { kind: "baseline", name: cd[1] });
  });
}

/** Best value of each objective so far (one subplot each) and hypervolume per generation.
 * The best so far is the API's `best_so_far` (the least value of the objective on the fronts
 * up to that generation); a row without it (an older API) falls back to `best`, which for
 * several objectives is the compromise point's and may rise.
 * @param {HTMLElement} el
 * @param {GenerationOut[]} generations
 * @param {Array<Pick<Quantity, "name" | "label" | "axis">>} objectives
 */
export function convergencePlot(el, generations, objectives) {
  const g = generations.map((r) => r.generation);
  const m = Math.max(1, objectives.length);
  const hv = generations.map((r) => r.hypervolume);
  const hasHv = hv.some((v) => v !== null && v !== undefined);
  const rows = m + (hasHv ? 1 : 0);
  /** @type {PlotSpec[]} */
  const traces = [];
  /** @type {PlotSpec} */
  const layout = { ...LAYOUT, grid: { rows, columns: 1, pattern: "independent" }, showlegend: false,
    height: 130 * rows + 70, margin: { l: 70, r: 16, t: 20, b: 40 } };
  for (let j = 0; j < m; j++) {
    const y = generations.map((r) => {
      const b = Array.isArray(r.best_so_far) ? r.best_so_far : r.best_so_far === undefined ? r.best : null;
      return Array.isArray(b) ? b[j] : b;
    });
    const ax = j === 0 ? "" : String(j + 1);
    traces.push({ type: "scatter", mode: "lines", x: g, y, xaxis: `x${ax}`, yaxis: `y${ax}`,
      name: `best ${objectives[j] ? objectives[j].label : ""} so far`, line: { color: COLORS[j], shape: "hv" } });
    layout[`yaxis${ax}`] = { title: { text: `best ${axis(objectives[j])} so far`, font: { size: 11 } } };
  }
  if (hasHv) {
    const ax = String(m + 1);
    traces.push({ type: "scatter", mode: "lines", x: g, y: hv, xaxis: `x${ax}`, yaxis: `y${ax}`,
      name: "hypervolume", line: { color: "#444" } });
    layout[`yaxis${ax}`] = { title: { text: "hypervolume", font: { size: 11 } } };
  }
  layout[`xaxis${rows === 1 ? "" : rows}`] = { title: { text: "generation" } };
  el.style.height = `${layout.height}px`;
  Plotly.react(el, traces, layout, CONFIG);
}

/**
 * One joint signal (q, qd, τ, …) of a motion (GET /jobs/{id}/motion), one line per joint.
 * @param {HTMLElement} el
 * @param {MotionOut} motion
 * @param {string} signalName
 */
export function jointPlot(el, motion, signalName) {
  const sig = motion.signals.find((s) => s.name === signalName) || motion.signals[0];
  if (!sig) { Plotly.react(el, [], { ...LAYOUT, title: { text: "no motion for this solution" } }, CONFIG); return; }
  const traces = sig.values.map((ys, j) => ({ type: "scatter", mode: "lines", x: motion.t, y: ys,
    name: motion.joint_names[j] || `joint ${j + 1}`, line: { color: COLORS[j % COLORS.length] } }));
  Plotly.react(el, traces, { ...LAYOUT, xaxis: { title: { text: "time [s]" } },
    yaxis: { title: { text: `${sig.label} [${sig.unit}]` } } }, CONFIG);
}

/**
 * Fronts of sweep cells overlaid: one colour and one legend entry per cell.
 * @param {HTMLElement} el
 * @param {SweepFrontsOut} fronts
 */
export function overlayPlot(el, fronts) {
  const m = fronts.objectives.length;
  const three = m >= 3;
  /** @type {PlotSpec[]} */
  const traces = [];
  fronts.cells.forEach((cell, i) => {
    const color = COLORS[i % COLORS.length];
    /** @type {CellFrontJob[]} */ (cell.jobs).forEach((job, k) => {
      const P = job.points;
      const t = { name: `cell ${cell.cell}: ${cell.label}`, legendgroup: `c${cell.cell}`, showlegend: k === 0,
        mode: "markers", marker: { color, size: three ? 3 : 6 }, text: P.map(() => `seed ${job.seed} · ${job.job_id.slice(0, 8)}`),
        customdata: P.map(() => job.job_id) };
      if (three) traces.push({ ...t, type: "scatter3d", x: P.map((p) => p[0]), y: P.map((p) => p[1]), z: P.map((p) => p[2]) });
      else traces.push({ ...t, type: "scatter", x: P.map((p) => p[0]), y: P.map((p) => (m > 1 ? p[1] : 0)) });
    });
  });
  const o = fronts.objectives;
  const layout = three
    ? { ...LAYOUT, scene: { xaxis: { title: { text: axis(o[0]) } }, yaxis: { title: { text: axis(o[1]) } }, zaxis: { title: { text: axis(o[2]) } } } }
    : { ...LAYOUT, xaxis: { title: { text: axis(o[0]) } }, yaxis: { title: { text: m > 1 ? axis(o[1]) : "" } } };
  Plotly.react(el, traces, layout, CONFIG);
  const plot = /** @type {PlotlyHTMLElement} */ (el);
  plot.removeAllListeners && plot.removeAllListeners("plotly_click");
  plot.on("plotly_click", (ev) => {
    const id = ev.points && ev.points[0] && ev.points[0].customdata;
    if (id) location.hash = `#/job/${id}`;
  });
}
