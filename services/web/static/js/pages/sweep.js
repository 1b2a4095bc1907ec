// One sweep: the grid as a table of cells (mean ± sd over seeds of every objective, metric and
// the hypervolume; the best cell of each objective highlighted), the fronts of the chosen
// cells overlaid in distinct colours, and a link into each job.
import { api, download } from "../api.js";
import { COLORS, overlayPlot, purge } from "../plots.js";
import { Viewer } from "../viewer.js";
import { fill, h, num, shortId } from "../ui.js";

/** @typedef {import("../api_types").SweepCellsOut} SweepCellsOut */
/** @typedef {import("../api_types").SweepFrontsOut} SweepFrontsOut */
/** @typedef {import("../api_types").SweepOut} SweepOut */

const POLL_MS = 3000;

/**
 * One sweep's page (#/sweep/ID) into `main`; its cleanup.
 * @param {HTMLElement} main
 * @param {string} sweepId
 * @returns {Promise<() => void>}
 */
export async function render(main, sweepId) {
  let alive = true;
  /** @type {number | undefined} */
  let timer;
  const table = h("table#cells-table");
  const plot = h("div.plot#overlay-plot");
  const summary = h("p.muted");
  /** @type {Set<number>} the cells whose fronts are drawn */
  const chosen = new Set();
  const viewerBox = h("div");
  /** @type {Viewer | null} */
  let viewer = null;
  /** @type {SweepCellsOut | null} */
  let cells = null;

  main.append(
    h("div.toolbar", h("h1", `Sweep ${shortId(sweepId)}`), h("span.spacer"),
      h("a", { href: `#/jobs?sweep_id=${sweepId}` }, "its jobs"),
      ...["csv", "parquet", "json"].map((f) => h("button.secondary", { dataset: { export: `cells-${f}` },
        on: { click: () => download(`/sweeps/${sweepId}/cells/export?format=${f}`, `cells.${f}`) } }, `cells ${f.toUpperCase()}`))),
    summary,
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

  async function load() {
    clearTimeout(timer);
    const [sweep, c] = await Promise.all([/** @type {Promise<SweepOut>} */ (api(`/sweeps/${sweepId}?limit=1`)),
      /** @type {Promise<SweepCellsOut>} */ (api(`/sweeps/${sweepId}/cells`))]);
    if (!alive) return;
    cells = c;
    summary.textContent = `${sweep.n_jobs} jobs, ${sweep.state}; swept: ${c.columns.join(", ") || "seeds only"}` +
      (c.hypervolume_ref ? `; hypervolumes against the sweep-wide reference point (${c.hypervolume_ref.map((v) => num(v)).join(", ")})` : "");
    if (!chosen.size) c.cells.slice(0, 4).forEach((cell) => chosen.add(cell.index));
    drawTable();
    await drawFronts();
    plot.dataset.sweepState = sweep.state; // table and fronts drawn for this state
    if (sweep.state !== "finished") timer = setTimeout(() => load().catch(() => {}), POLL_MS);
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

  await load();
  return () => { alive = false; clearTimeout(timer); purge(plot); };
}
