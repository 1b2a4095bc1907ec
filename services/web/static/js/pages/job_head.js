// The job page's head: name, status badge, sweep link, and the job's actions — Cancel (while it
// runs), Re-run with a new seed, the spec and recording downloads, and Delete (DELETE
// /jobs/{id}: the job and everything stored for it, its artifact files too). Delete asks first
// in a dialog (delete_dialog.js); the API refuses a queued or running job (409: cancel it
// first) and the dialog shows its message; once deleted the page goes to the jobs list.
import { api, download } from "../api.js";
import { fill, h, jobBadge, shortId, TERMINAL } from "../ui.js";
import { deleteDialog } from "./delete_dialog.js";
import { rerun } from "./jobs.js";

/** @typedef {import("../api_types").JobDetail} JobDetail */

/**
 * @param {HTMLElement} el where the head goes
 * @param {() => void} onChanged called after an action changed the job (cancel)
 * @returns {{ draw: (job: JobDetail) => void }}
 */
export function jobHead(el, onChanged) {
  const dialog = deleteDialog({ title: "Delete this job?", after: "#/jobs",
    note: "Its trials, front, result, events and artifact files (recordings) are removed; "
      + "this cannot be undone. It frees storage quota." });
  // the toolbar is redrawn on every refresh; the dialog stays (a redraw must not close it)
  const bar = h("div");
  el.append(bar, dialog.el);

  /** @param {JobDetail} job */
  function ask(job) {
    dialog.ask(`/jobs/${job.id}`, `Job ${job.name ? `“${job.name}” ` : ""}${shortId(job.id)} (${job.status})`
      + (TERMINAL.has(job.status) ? "." : ": it has not finished, so the server refuses until it is cancelled."));
  }

  /** @param {JobDetail} job */
  function draw(job) {
    fill(bar, h("div.toolbar",
      h("h1", job.name || `Job ${shortId(job.id)}`), jobBadge(job),
      job.sweep_id ? h("a", { href: `#/sweep/${job.sweep_id}` }, `sweep ${shortId(job.sweep_id)}`) : null,
      h("span.spacer"),
      !TERMINAL.has(job.status) ? h("button.danger", { dataset: { action: "cancel" }, on: { click: async () => {
        await api(`/jobs/${job.id}/cancel`, { method: "POST" }); onChanged(); } } }, "Cancel") : null,
      h("button.secondary", { dataset: { action: "rerun" }, on: { click: async () => { location.hash = `#/job/${(await rerun(job.id)).id}`; } } }, "Re-run (new seed)"),
      h("button.secondary", { dataset: { export: "spec" }, on: { click: () => download(`/jobs/${job.id}/spec.yaml`, "spec.yaml") } }, "Spec YAML"),
      job.status === "succeeded" ? h("button.secondary", { on: { click: () => download(`/jobs/${job.id}/recording`, "job.rrd") } }, "Recording .rrd") : null,
      h("button.danger", { dataset: { action: "delete" }, title: "Delete the job and everything stored for it",
        on: { click: () => ask(job) } }, "Delete")));
  }

  return { draw };
}
