// One job: status and progress (polled while it runs), convergence (best per objective so far
// and hypervolume per generation), the Pareto front (click a point, a table row or a baseline
// to see that solution's joint signals and its Rerun recording), the front's points with their
// objectives, metrics and decision variables, metrics, spec, downloads. Once it succeeded, its
// verdict first: red with each violated constraint and by how much when the reported optimum
// is infeasible, green when it meets every constraint; and the task it ran (the rule that
// derived each robot-relative parameter from its robot). Beside the trials, each variable's
// importance for each objective. The head has the job's actions (Delete among them).
import { api, download } from "../api.js";
import { keepCurrent } from "../live.js";
import { convergencePlot, jointPlot, purge } from "../plots.js";
import { Viewer } from "../viewer.js";
import { bar, best, clear, errorText, fill, h, num, shortId, TERMINAL, violationText, when } from "../ui.js";
import { frontSteering } from "./job_front.js";
import { jobHead } from "./job_head.js";
import { importanceCard } from "./job_importance.js";
import { drawMetrics } from "./job_metrics.js";
import { trialsCard } from "./job_trials.js";

/** @typedef {import("../api_types").FrontOut} FrontOut */
/** @typedef {import("../api_types").GapOut} GapOut */
/** @typedef {import("../api_types").GenerationOut} GenerationOut */
/** @typedef {import("../api_types").GenerationPage} GenerationPage */
/** @typedef {import("../api_types").JobDetail} JobDetail */
/** @typedef {import("../api_types").LiveFrontOut} LiveFrontOut */
/** @typedef {import("../api_types").MotionOut} MotionOut */
/** @typedef {import("../api_types").Quantity} Quantity */
/** @typedef {import("../api_types").ResultOut} ResultOut */
/** @typedef {import("../api_types").TaskOut} TaskOut */
/** @typedef {import("../plots.js").Selection} Selection */

const POLL_MS = 1500;
// While the server pushes the job's progress (GET /jobs/{id}/events), a slow poll only in case.
const SAFETY_POLL_MS = 15000;
// How often the page asks again for a front whose points' metrics are still being computed.
const METRICS_RETRY_MS = 3000;

/**
 * One job's page (#/job/ID) into `main`; its cleanup.
 * @param {HTMLElement} main
 * @param {string} jobId
 * @returns {Promise<() => void>}
 */
export async function render(main, jobId) {
  let alive = true;
  const head = h("div");
  const verdict = h("div#verdict");
  const progress = h("div.card");
  const conv = h("div.plot.small#convergence");
  const frontEl = h("div.plot#front-plot");
  const frontControls = h("div.toolbar#front-controls");
  const frontTable = h("table#front-table");
  const motionCard = h("div.card#motion");
  const viewer = new Viewer();
  const metrics = h("div.card#metrics");
  const spec = h("div.card");
  const trials = trialsCard(jobId, (t) => pick({ kind: "trial", index: t }));
  const importance = importanceCard(jobId);
  const steer = frontSteering(frontControls, frontEl, (sel) => pick(sel));
  /** @type {JobDetail | null} */
  let current = null;
  /** @type {HTMLElement[]} */
  const plots = [conv, frontEl];
  /** @type {FrontOut | null} */
  let front = null;
  /** @type {number | undefined} */
  let metricsTimer;
  /** @type {Selection | null} */
  let selected = null;
  /** @type {number | null} */
  let lastGen = null;
  /** @type {GenerationOut[]} */
  let generations = [];
  let signal = "q";

  main.append(head, verdict, progress,
    h("div.row",
      h("div.card.grow", h("h2", "Convergence"), conv),
      h("div.card.grow", h("h2", "Pareto front"), h("p.muted", "Click a point, a row or a baseline to see its motion."), frontControls, frontEl)),
    h("div.card", h("div.toolbar", h("h2", "Front points"), h("span.spacer"),
      ...["csv", "parquet", "json"].map((f) => h("button.secondary", { dataset: { export: `front-${f}` },
        on: { click: () => download(`/jobs/${jobId}/front/export?format=${f}`, `front.${f}`) } }, `front ${f.toUpperCase()}`)),
      ...["csv", "parquet"].map((f) => h("button.secondary", { dataset: { export: `history-${f}` },
        on: { click: () => download(`/jobs/${jobId}/history/export?format=${f}`, `history.${f}`) } }, `history ${f.toUpperCase()}`))),
      h("div.scroll", frontTable)),
    h("div.row", h("div.grow", motionCard), h("div.card.grow", h("h2", "Rerun recording"), viewer.el)),
    trials.el, importance.el, metrics, spec);

  // Live: the server pushes an event when the job's generation or status changes; the page
  // redraws then. Where the stream cannot be opened (or breaks), the page polls.
  const following = keepCurrent(`/jobs/${jobId}/events`, refresh, { pollMs: POLL_MS, safetyMs: SAFETY_POLL_MS });
  const actions = jobHead(head, () => following.refresh());

  // The running job's current front (objective vectors of its last stored generation).
  async function drawLiveFront() {
    /** @type {LiveFrontOut} */
    const live = await api(`/jobs/${jobId}/front/live`);
    if (alive && !front) steer.drawLive(live);
  }

  /** @returns {Promise<boolean>} whether the job has finished */
  async function refresh() {
    /** @type {JobDetail} */
    const job = await api(`/jobs/${jobId}`);
    if (!alive) return true;
    current = job;
    actions.draw(job);
    drawVerdict(job);
    drawProgress(job);
    /** @type {GenerationPage} */
    const page = await api(`/jobs/${jobId}/generations${lastGen === null ? "" : `?after=${lastGen}`}`);
    generations = generations.concat(page.items);
    if (page.items.length) lastGen = page.next_after;
    if (generations.length) convergencePlot(conv, generations, front ? front.objectives : objectivesOf(generations));
    if (page.items.length || !TERMINAL.has(job.status) || lastGen === null) await trials.refresh();
    if (TERMINAL.has(job.status)) {
      importance.finished();
      if (job.status === "succeeded" && !front) await loadResult(job);
      return true;
    }
    await drawLiveFront().catch(() => {});
    return false;
  }

  /**
   * Placeholder objectives f1, f2, … (as many as a generation's best has) until the front
   * gives their names.
   * @param {GenerationOut[]} gens
   */
  function objectivesOf(gens) {
    const b = gens[0] && gens[0].best;
    const m = Array.isArray(b) ? b.length : 1;
    return Array.from({ length: m }, (_, j) => ({ name: `f${j + 1}`, label: `f${j + 1}`, unit: "", axis: `f${j + 1}` }));
  }

  // The verdict of a succeeded job (GET /jobs/{id}: feasible, violations); the task's rules
  // are added once the result is loaded.
  /** @type {JobDetail | null} */
  let verdictJob = null;
  /**
   * @param {JobDetail} job
   * @param {TaskOut | null} [task]
   * @param {GapOut | null} [gap]
   */
  function drawVerdict(job, task = null, gap = null) {
    verdictJob = job;
    if (job.status !== "succeeded" || job.feasible === null || job.feasible === undefined) {
      verdict.className = "";
      fill(verdict, task || gap ? h("div.card", gapBlock(gap), task ? taskBlock(task) : null) : null);
      return;
    }
    const ok = job.feasible === true;
    verdict.className = `card verdict ${ok ? "feasible" : "infeasible"}`;
    verdict.dataset.verdict = ok ? "feasible" : "infeasible";
    fill(verdict,
      h("h2", ok ? "Feasible: the reported optimum meets every constraint"
        : "Infeasible: the reported optimum violates a constraint"),
      ok ? null : h("ul.violations#violations", job.violations.map((v) => h("li", { dataset: { constraint: v.constraint } }, violationText(v)))),
      ok ? null : h("p.muted", "The run completed (status succeeded), but this answer breaks the constraints above: "
        + "relax them, change the task, or give the optimiser more budget."),
      gapBlock(gap),
      task ? taskBlock(task) : null);
  }

  // How far a single-objective optimum is from the best its problem allows (GET
  // /jobs/{id}/result: gap), or why there is no such reference.
  /** @param {GapOut | null} gap */
  function gapBlock(gap) {
    if (!gap || !gap.objective) return null;
    if (gap.reference === null || gap.reference === undefined) {
      return h("p.muted#gap", { dataset: { gap: "none" } }, `No optimality gap: ${gap.reason || "no reference"}.`);
    }
    const pct = gap.pct === null || gap.pct === undefined ? "—" : `${gap.pct >= 0 ? "+" : ""}${num(gap.pct, 3)} %`;
    return h("p#gap", { dataset: { gap: "reference" } },
      h("strong", `Gap to the ${gap.kind || "reference"}: ${pct}`),
      ` — ${gap.objective} ${num(gap.value)} vs ${num(gap.reference)}`,
      gap.method ? h("span.muted", ` (${gap.method})`) : null);
  }

  /** @param {TaskOut} task */
  function taskBlock(task) {
    const rules = Object.entries(task.rules || {});
    if (!rules.length && !task.preset) return null;
    return h("section#task", h("h2", "Task"),
      task.preset ? h("p", `what the spec leaves out is the paper's: ${task.preset}`) : null,
      rules.length ? h("p", "derived from the robot:") : null,
      rules.length ? h("ul.task-rules", rules.map(([k, r]) => h("li", { dataset: { field: k } }, h("span.mono", k), `: ${r}`))) : null);
  }

  /** @param {JobDetail} job */
  function drawProgress(job) {
    fill(progress, 
      h("dl.kv",
        h("dt", "study"), h("dd", job.kind || "—"),
        h("dt", "progress"), h("dd", bar(job.progress, `generation ${job.generation} of ${job.total_generations || "?"}`)),
        h("dt", "best so far"), h("dd", best(job.best_objective)),
        h("dt", "attempts"), h("dd", String(job.attempts)),
        h("dt", "created / started / finished"), h("dd", `${when(job.created_at)} · ${when(job.started_at)} · ${when(job.finished_at)}`),
        h("dt", "id"), h("dd.mono", job.id)),
      job.error ? h("p.error", job.error) : null,
      job.warnings.length ? h("ul.warn-list", job.warnings.map((w) => h("li", w))) : null);
    fill(spec, h("h2", "Spec"), h("pre.spec", JSON.stringify(job.spec, null, 2)));
  }

  /** @param {JobDetail} job a succeeded job */
  async function loadResult(job) {
    const [f, result] = await Promise.all([/** @type {Promise<FrontOut>} */ (api(`/jobs/${job.id}/front`)),
      /** @type {Promise<ResultOut>} */ (api(`/jobs/${job.id}/result`))]);
    if (!alive) return;
    front = f;
    if ((result.task || result.gap) && verdictJob) drawVerdict(verdictJob, result.task, result.gap);
    if (generations.length) convergencePlot(conv, generations, front.objectives);
    drawFront();
    drawFrontTable(front);
    drawMetrics(metrics, front, result);
    if (front.point_metrics === "pending") metricsTimer = setTimeout(() => reloadPointMetrics(job).catch(() => {}), METRICS_RETRY_MS);
    const first = front.best_index ?? (front.points[0] && front.points[0].index);
    if (first !== undefined && first !== null) pick({ kind: "point", index: first });
  }

  // The points' metrics are decoded on the server the first time the front is asked for; a
  // large front answers "pending" first: ask again, then redraw the table (selection kept).
  /** @param {JobDetail} job */
  async function reloadPointMetrics(job) {
    /** @type {FrontOut} */
    const f = await api(`/jobs/${job.id}/front`);
    if (!alive) return;
    if (f.point_metrics === "pending") {
      metricsTimer = setTimeout(() => reloadPointMetrics(job).catch(() => {}), METRICS_RETRY_MS);
      return;
    }
    front = f;
    drawFrontTable(front);
    markSelected();
  }

  function drawFront() { if (front) steer.draw(front, selected); }

  /** @param {FrontOut} front */
  function drawFrontTable(front) {
    clear(frontTable);
    const o = front.objectives;
    const nx = Math.min(front.variables.length, 12);
    // metric columns: readable name and unit (the key on hover), those some point has, but
    // not an objective again (its column is there already)
    const objectiveNames = new Set(o.map((q) => q.name));
    const ms = front.metrics.filter((q) => !objectiveNames.has(q.name)
      && front.points.some((p) => p.metrics && q.name in p.metrics));
    const note = front.point_metrics === "pending" ? "metrics: being computed…"
      : front.point_metrics === "unavailable" ? `metrics unavailable: ${front.point_metrics_note || ""}` : null;
    frontTable.append(h("thead",
      note ? h("tr", h("th.muted", { colSpan: 1 + o.length + ms.length + nx }, note)) : null,
      h("tr", h("th", "#"), o.map((q) => h("th.num", q.axis)),
        ms.map((q) => h("th.num.metric", { title: q.name, dataset: { metric: q.name } }, q.axis)),
        front.variables.slice(0, nx).map((v) => h("th.num", v.label)))));
    const body = h("tbody");
    for (const p of front.points) {
      const pm = p.metrics || {};
      const tr = h("tr.clickable", { dataset: { point: p.index } }, h("td", String(p.index)),
        p.objectives.map((v) => h("td.num", num(v))), ms.map((q) => h("td.num", num(pm[q.name]))),
        p.x.slice(0, nx).map((v) => h("td.num", num(v))));
      tr.addEventListener("click", () => pick({ kind: "point", index: p.index }));
      body.append(tr);
    }
    for (const b of front.baselines) {
      const tr = h("tr.clickable", { dataset: { baseline: b.name } }, h("td", h("em", `baseline ${b.name}`)),
        b.objectives.map((v) => h("td.num", num(v))), ms.map((q) => h("td.num", num(b.metrics[q.name]))),
        front.variables.slice(0, nx).map(() => h("td")));
      tr.addEventListener("click", () => pick({ kind: "baseline", name: b.name }));
      body.append(tr);
    }
    const paperOut = front.paper;
    for (const p of (paperOut && paperOut.marks) || []) {
      body.append(h("tr.paper", { dataset: { paper: p.label } }, h("td", h("em", `${p.label} (${paperOut?.source})`)),
        p.objectives.map((v) => h("td.num", num(v))), ms.map(() => h("td")), front.variables.slice(0, nx).map(() => h("td"))));
    }
    frontTable.append(body);
  }

  function markSelected() {
    for (const tr of frontTable.querySelectorAll("tr.selected")) tr.classList.remove("selected");
    const sel = selected;
    if (!sel) return null;
    if (sel.kind === "trial") return null;
    const row = sel.kind === "point" ? frontTable.querySelector(`tr[data-point="${sel.index}"]`)
      : frontTable.querySelector(`tr[data-baseline="${CSS.escape(sel.name)}"]`);
    if (row) row.classList.add("selected");
    return row;
  }

  /** @param {Selection} sel */
  async function pick(sel) {
    if (!front && !(sel.kind === "trial" && current && current.status === "succeeded")) return;
    selected = sel;
    const row = markSelected();
    if (row) row.scrollIntoView({ block: "nearest" });
    trials.mark(sel.kind === "trial" ? sel.index : null);
    if (front) drawFront();
    const title = sel.kind === "point" ? `front point ${sel.index}` : sel.kind === "trial" ? `trial ${sel.index}` : `baseline ${sel.name}`;
    fill(motionCard, h("h2", `Motion of ${title}`), h("p.muted", "decoding…"));
    const q = sel.kind === "point" ? `point=${sel.index}` : sel.kind === "trial" ? `trial=${sel.index}` : `baseline=${encodeURIComponent(sel.name)}`;
    try {
      /** @type {MotionOut} */
      const motion = await api(`/jobs/${jobId}/motion?${q}`);
      if (selected !== sel || !alive) return;
      drawMotion(motion, title);
      if (sel.kind === "point") viewer.open(`/jobs/${jobId}/pareto/${sel.index}/recording`, `${title} of ${shortId(jobId)}`);
      else if (sel.kind === "trial") viewer.open(`/jobs/${jobId}/trials/${sel.index}/recording`, `${title} of ${shortId(jobId)}`);
      else viewer.open(`/jobs/${jobId}/baselines/${encodeURIComponent(sel.name)}/recording`, `${title} of ${shortId(jobId)}`);
    } catch (err) {
      fill(motionCard, h("h2", `Motion of ${title}`), h("p.error", errorText(err)));
    }
  }

  /**
   * @param {MotionOut} motion
   * @param {string} title
   */
  function drawMotion(motion, title) {
    const plot = h("div.plot#joint-plot");
    plots.push(plot);
    const tabs = h("div.tabs", motion.signals.map((s) => h(`button${s.name === signal ? ".on" : ""}`, {
      dataset: { signal: s.name }, on: { click: () => { signal = s.name; drawMotion(motion, title); } } }, s.name)));
    const obj = Object.entries(motion.objectives).map(([k, v]) => `${k} = ${num(v)}`).join(" · ");
    const labels = Object.fromEntries((front ? front.metrics : []).map((q) => [q.name, q]));
    const metricRows = Object.entries(motion.metrics).map(([k, v]) => {
      const q = labels[k] || { label: k, unit: "" };
      return h("tr", h("td", q.label), h("td.num", num(v)), h("td", q.unit));
    });
    fill(motionCard, h("h2", `Motion of ${title}`), h("p", obj), tabs, plot,
      motion.t.length ? h("p.muted", `${motion.joint_names.length} joints, ${motion.source_samples} samples (${motion.t.length} plotted)`) : null,
      metricRows.length ? h("details", h("summary", `its metrics (${metricRows.length})`),
        h("table#point-metrics", h("tbody", metricRows))) : null);
    jointPlot(plot, motion, signal);
  }

  await following.first();
  return () => { alive = false; following.stop(); clearTimeout(metricsTimer); plots.forEach(purge); };
}
