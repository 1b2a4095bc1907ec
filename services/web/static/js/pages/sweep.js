// One sweep: the grid as a table of cells (mean ± sd over seeds of every objective, metric and
// the hypervolume; the best cell of each objective highlighted), the fronts of the chosen
// cells overlaid in distinct colours, and a link into each job. Live while it runs: the
// server pushes the sweep's job counts and progress (GET /sweeps/{id}/events) and the page
// redraws the progress at once and the cells when a job has finished; where the stream cannot
// be opened, it polls. Delete (DELETE /sweeps/{id}: every job of the sweep with everything
// stored for it, then the sweep) asks first in a dialog (delete_dialog.js); the API refuses
// while a job is queued or running (409: cancel it first) and the dialog shows its message;
// once deleted the page goes to the sweeps list.
import { api, download } from "../api.js";
import { keepCurrent } from "../live.js";
import { COLORS, overlayPlot, purge } from "../plots.js";
import { Viewer } from "../viewer.js";
import { badge, bar, fill, h, num, shortId } from "../ui.js";
import { deleteDialog } from "./delete_dialog.js";

/** @typedef {import("../api_types").SweepCellsOut} SweepCellsOut */
/** @typedef {import("../api_types").SweepFrontsOut} SweepFrontsOut */
/** @typedef {import("../api_types").SweepOut} SweepOut */
/**
 * What GET /sweeps/{id}/events pushes (`progress`): the jobs per status, the generations done
 * and planned summed over the jobs, the mean fraction done; `terminal` once every job finished.
 * @typedef {{ state: string, n_jobs: number, counts: Record<string, number>, generation?: number,
 *   total_generations?: number, progress?: number, terminal?: boolean }} SweepProgress
 */

const POLL_MS = 3000;
// While the server pushes the sweep's progress, a slow poll only in case.
const SAFETY_POLL_MS = 15000;

/** @param {Record<string, number>} counts @returns {string} the counts, comparable */
const countsKey = (counts) => Object.keys(counts).sort().map((k) => `${k}=${counts[k]}`).join(",");

/**
 * One sweep's page (#/sweep/ID) into `main`; its cleanup.
 * @param {HTMLElement} main
 * @param {string} sweepId
 * @returns {Promise<() => void>}
 */
export async function render(main, sweepId) {
  let alive = true;
  const table = h("table#cells-table");
  const plot = h("div.plot#overlay-plot");
  const summary = h("p.muted");
  const progress = h("div#sweep-progress");
  /** @type {string | null} the job counts the cells were drawn for */
  let loadedCounts = null;
  /** @type {SweepProgress | null} the last pushed progress not yet acted on */
  let pushed = null;
  /** @type {Set<number>} the cells whose fronts are drawn */
  const chosen = new Set();
  const viewerBox = h("div");
  /** @type {Viewer | null} */
  let viewer = null;
  /** @type {SweepCellsOut | null} */
  let cells = null;
  /** @type {SweepOut | null} the sweep as last loaded */
  let shown = null;
  const dialog = deleteDialog({ title: "Delete this sweep?", after: "#/sweeps",
    note: "Every job of the sweep is deleted with its trials, front, result, events and artifact "
      + "files (recordings), then the sweep; this cannot be undone. It frees storage quota." });

  function askDelete() {
    const finished = shown ? shown.state === "finished" || shown.state === "empty" : true;
    dialog.ask(`/sweeps/${sweepId}`, `Sweep ${shortId(sweepId)}`
      + (shown ? ` (${shown.n_jobs} jobs, ${shown.state})` : "")
      + (finished ? "." : ": some of its jobs have not finished, so the server refuses until the sweep is cancelled."));
  }

  main.append(
    h("div.toolbar", h("h1", `Sweep ${shortId(sweepId)}`), h("span.spacer"),
      h("a", { href: `#/jobs?sweep_id=${sweepId}` }, "its jobs"),
      ...["csv", "parquet", "json"].map((f) => h("button.secondary", { dataset: { export: `cells-${f}` },
        on: { click: () => download(`/sweeps/${sweepId}/cells/export?format=${f}`,
          `legopt-cells-${shortId(sweepId)}.${f}`) } }, `cells ${f.toUpperCase()}`)),
      ...["csv", "parquet", "json"].map((f) => h("button.secondary", { dataset: { export: `sweep-jobs-${f}` },
        on: { click: () => download(`/sweeps/${sweepId}/jobs/export?format=${f}`,
          `legopt-sweep-jobs-${shortId(sweepId)}.${f}`) } }, `jobs ${f.toUpperCase()}`)),
      h("button.danger", { dataset: { action: "delete" }, title: "Delete the sweep, its jobs and everything stored for them",
        on: { click: askDelete } }, "Delete")),
    dialog.el, summary, progress,
    h("div.card", h("h2", "Cells (mean ± sd over seeds)"), h("div.scroll.full", table)),
    h("div.card", h("h2", "Fronts of the chosen cells"), h("p.muted", "Tick cells in the table; click a point to open its job."), plot),
    h("div.card", h("div.toolbar", h("h2", "Recordings of the chosen cells, merged"), h("span.spacer"),
      h("button.secondary#open-merged", { on: { click: openMerged } }, "Open in the viewer")), viewerBox));

  function openMerged() {
    if (!cells) return;
    const ids = cells.cells.filter((c) => chosen.has(c.index)).flatMap((c) => c.job_ids).slice(0, 32);
    if (!viewer) { viewer = new Viewer(); viewerBox.append(viewer.el); }
    viewer.open(`/sweeps/${sweepId}/recording?${ids.map((i) => `jobs=${i}`).join("&")}`, `sweep ${shortId(sweepId)}`);
  }

  /** @param {SweepProgress} p */
  function drawProgress(p) {
    const done = ["succeeded", "failed", "cancelled"].reduce((t, k) => t + (p.counts[k] || 0), 0);
    const fraction = p.progress ?? (p.n_jobs ? done / p.n_jobs : 0);
    const gens = p.total_generations ? ` · generation ${p.generation} of ${p.total_generations} over the jobs` : "";
    progress.dataset.state = p.state;
    progress.dataset.generation = String(p.generation ?? "");
    fill(progress, h("p", bar(fraction, `${done} of ${p.n_jobs} jobs finished${gens}`), " ",
      Object.entries(p.counts).filter(([, n]) => n > 0).map(([k, n]) => [badge(k), ` ${n} `])));
  }

  // A pushed event redraws the progress at once; the cells and fronts only change when a job
  // finishes, so they are reloaded when the counts changed (and on every poll).
  /** @returns {Promise<boolean>} whether the sweep has finished */
  async function refresh() {
    const p = pushed;
    pushed = null;
    if (p && !p.terminal && countsKey(p.counts) === loadedCounts) return false;
    return load();
  }

  /** @returns {Promise<boolean>} whether the sweep has finished */
  async function load() {
    const [sweep, c] = await Promise.all([/** @type {Promise<SweepOut>} */ (api(`/sweeps/${sweepId}?limit=1`)),
      /** @type {Promise<SweepCellsOut>} */ (api(`/sweeps/${sweepId}/cells`))]);
    if (!alive) return true;
    cells = c;
    shown = sweep;
    summary.textContent = `${sweep.n_jobs} jobs, ${sweep.state}; swept: ${c.columns.join(", ") || "seeds only"}` +
      (c.hypervolume_ref ? `; hypervolumes against the sweep-wide reference point (${c.hypervolume_ref.map((v) => num(v)).join(", ")})` : "");
    if (!chosen.size) c.cells.slice(0, 4).forEach((cell) => chosen.add(cell.index));
    drawTable();
    await drawFronts();
    plot.dataset.sweepState = sweep.state; // table and fronts drawn for this state
    loadedCounts = countsKey(sweep.counts);
    // the pushed progress has the generations too: keep it while the stream is open
    if (!live.streaming()) drawProgress(sweep);
    return sweep.state === "finished" || sweep.state === "empty";
  }

  function drawTable() {
    const grid = cells;
    if (!grid) return;
    const stats = grid.stat_columns;
    fill(table, h("thead", h("tr", h("th", ""), h("th", "cell"), grid.columns.map((p) => h("th", p)),
      h("th", "jobs"), stats.map((q) => h("th.num", q.axis)))));
    const body = h("tbody");
    grid.cells.forEach((cell) => {
      const box = h("input", { type: "checkbox", checked: chosen.has(cell.index), dataset: { cell: cell.index }, on: { change: (ev) => {
        if (/** @type {HTMLInputElement} */ (ev.target).checked) chosen.add(cell.index); else chosen.delete(cell.index);
        drawFronts();
      } } });
      const color = COLORS[[...chosen].sort((a, b) => a - b).indexOf(cell.index) % COLORS.length];
      body.append(h("tr", { dataset: { cellRow: cell.index } },
        h("td", box), h("td", chosen.has(cell.index) ? h("span.legend-swatch", { style: `background:${color}` }) : null, String(cell.index)),
        grid.columns.map((p) => h("td", JSON.stringify(cell.values[p]))),
        h("td", cell.job_ids.map((id, k) => h("a.tag", { href: `#/job/${id}`, title: `seed ${cell.seeds[k]}` }, shortId(id)))),
        stats.map((q) => {
          const s = cell.stats[q.name];
          const isBest = grid.best[q.name] === cell.index;
          return h(`td.num${isBest ? ".best" : ""}`, s && s.mean !== null ? `${num(s.mean)} ± ${num(s.sd)}` : "—",
            s && s.n ? h("span.muted", ` (${s.n})`) : null);
        })));
    });
    table.append(body);
  }

  async function drawFronts() {
    const ids = [...chosen].sort((a, b) => a - b);
    if (!ids.length) { purge(plot); return; }
    /** @type {SweepFrontsOut} */
    const fronts = await api(`/sweeps/${sweepId}/fronts?${ids.map((i) => `cell=${i}`).join("&")}`);
    if (!alive) return;
    overlayPlot(plot, fronts);
    drawTable();
  }

  const live = keepCurrent(`/sweeps/${sweepId}/events`, refresh, {
    pollMs: POLL_MS,
    safetyMs: SAFETY_POLL_MS,
    onEvent: (name, data) => {
      if (name !== "progress" || !alive) return;
      pushed = /** @type {SweepProgress} */ (data);
      drawProgress(pushed);
    },
  });
  await live.first();
  return () => { alive = false; live.stop(); purge(plot); };
}
