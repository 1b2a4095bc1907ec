// The job page's front plot, steerable: which objectives it shows (any 2 or 3 of them) and
// whether the baselines and the paper's values may widen its axes (by default the axes fit the
// front, so a far baseline does not squash it flat). One objective has no front: the card says
// so (the convergence plot and the optimum's motion are the answer). While the job runs, the
// plot shows the current front (GET /jobs/{id}/front/live), not yet clickable.
import { frontPlot, purge } from "../plots.js";
import { fill, h } from "../ui.js";

/** @typedef {import("../api_types").FrontOut} FrontOut */
/** @typedef {import("../api_types").LiveFrontOut} LiveFrontOut */
/** @typedef {import("../plots.js").Selection} Selection */
/** @typedef {import("../plots.js").FrontView} FrontView */

/**
 * @param {HTMLElement} controls where the objective pickers go
 * @param {HTMLElement} plotEl the plot
 * @param {(sel: Selection) => void} onPick
 * @returns {{ draw: (front: FrontOut, selected: Selection | null) => void, drawLive: (live: LiveFrontOut) => void }}
 */
export function frontSteering(controls, plotEl, onPick) {
  /** @type {FrontView} */
  const view = { axes: null, fitBaselines: false };
  /** @type {FrontOut | null} */
  let last = null;
  /** @type {Selection | null} */
  let lastSel = null;

  /** @param {FrontOut} f @param {Selection | null} selected */
  function draw(f, selected) {
    last = f;
    lastSel = selected;
    const m = f.objectives.length;
    if (m < 2) {
      purge(plotEl);
      fill(controls);
      fill(plotEl, h("p.muted#single-objective", `One objective (${f.objectives[0] ? f.objectives[0].axis : "f1"}): `
        + "there is no front to draw. Its convergence is the plot at left; the best solution is "
        + `${f.points.length ? `point ${f.best_index ?? f.points[0].index}, ` : ""}whose motion is shown below.`));
      return;
    }
    const axes = view.axes || (m >= 3 ? [0, 1, 2] : [0, 1]);
    const marks = f.baselines.length || (f.paper && f.paper.marks.length);
    const fitBox = /** @type {HTMLInputElement} */ (h("input#front-fit-baselines", { type: "checkbox", checked: !!view.fitBaselines }));
    fitBox.addEventListener("change", () => { view.fitBaselines = fitBox.checked; redraw(); });
    fill(controls, h("label", "x ", picker(f, "front-x", axes[0], false)), h("label", " y ", picker(f, "front-y", axes[1], false)),
      m >= 3 ? h("label", " z ", picker(f, "front-z", axes[2] ?? null, true)) : null,
      marks ? h("label", " ", fitBox, " fit baselines") : null);
    frontPlot(plotEl, f, onPick, selected, { axes, fitBaselines: view.fitBaselines });
  }

  function redraw() { if (last) draw(last, lastSel); }

  /**
   * A select of the objectives (`optional`: also "none").
   * @param {FrontOut} f @param {string} id @param {number | null} value @param {boolean} optional
   */
  function picker(f, id, value, optional) {
    const sel = /** @type {HTMLSelectElement} */ (h(`select#${id}`,
      optional ? h("option", { value: "" }, "—") : null,
      f.objectives.map((q, j) => h("option", { value: String(j), selected: j === value }, q.axis))));
    if (value === null) sel.value = "";
    sel.addEventListener("change", () => {
      const picked = ["front-x", "front-y", "front-z"]
        .map((k) => /** @type {HTMLSelectElement | null} */ (controls.querySelector(`#${k}`)))
        .map((e) => (e && e.value !== "" ? Number(e.value) : null))
        .filter((v) => v !== null);
      view.axes = /** @type {number[]} */ ([...new Set(picked)]);
      redraw();
    });
    return sel;
  }

  /** @param {LiveFrontOut} live */
  function drawLive(live) {
    if (!live.points.length || live.objectives.length < 2) return;
    /** @type {FrontOut} */
    const f = /** @type {FrontOut} */ (/** @type {unknown} */ ({
      job_id: live.job_id, status: "running", objectives: live.objectives, variables: [], metrics: [],
      points: live.points.map((o, i) => ({ index: i, objectives: o, x: [], metrics: null })),
      point_metrics: "unavailable", point_metrics_note: null, best_index: null, baselines: [], paper: null,
    }));
    frontPlot(plotEl, f, () => {}, null, { axes: view.axes });
  }

  return { draw, drawLive };
}
