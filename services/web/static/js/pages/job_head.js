// The job page's head: name, status badge, sweep link, and the job's actions — Cancel (while it
// runs), Re-run with a new seed, the spec and recording downloads, and Delete (DELETE
// /jobs/{id}: the job and everything stored for it, its artifact files too). Delete asks first
// in a dialog; the API refuses a queued or running job (409: cancel it first) and the dialog
// shows its message; once deleted the page goes to the jobs list.
import { api, ApiError, download } from "../api.js";
import { errorText, fill, h, jobBadge, shortId, TERMINAL } from "../ui.js";
import { rerun } from "./jobs.js";

/** @typedef {import("../api_types").JobDetail} JobDetail */

/**
 * @param {HTMLElement} el where the head goes
 * @param {() => void} onChanged called after an action changed the job (cancel)
 * @returns {{ draw: (job: JobDetail) => void }}
 */
export function jobHead(el, onChanged) {
  const message = h("p#delete-message");
  const error = h("p.error#delete-error");
  const confirmButton = /** @type {HTMLButtonElement} */ (h("button.danger#delete-confirm", "Delete"));
  const dialog = /** @type {HTMLDialogElement} */ (h("dialog#delete-dialog",
    h("h2", "Delete this job?"), message,
    h("p.muted", "Its trials, front, result, events and artifact files (recordings) are removed; "
      + "this cannot be undone. It frees storage quota."),
    error,
    h("div.toolbar", h("span.spacer"),
      h("button.secondary#delete-cancel", { type: "button", on: { click: () => dialog.close() } }, "Keep it"),
      confirmButton)));
  // the toolbar is redrawn on every refresh; the dialog stays (a redraw must not close it)
  const bar = h("div");
  el.append(bar, dialog);
  /** @type {JobDetail | null} */
  let shown = null;

  confirmButton.addEventListener("click", async () => {
    if (!shown) return;
    const id = shown.id;
    confirmButton.disabled = true;
    fill(error);
    try {
      await api(`/jobs/${id}`, { method: "DELETE" });
      dialog.close();
      location.hash = "#/jobs";
    } catch (err) {
      // 409: still queued or running (the API says to cancel it first); 404: already gone
      error.dataset.status = err instanceof ApiError ? String(err.status) : "";
      fill(error, errorText(err));
    } finally {
      confirmButton.disabled = false;
    }
  });

  /** @param {JobDetail} job */
  function ask(job) {
    fill(message, `Job ${job.name ? `“${job.name}” ` : ""}${shortId(job.id)} (${job.status})`
      + (TERMINAL.has(job.status) ? "." : ": it has not finished, so the server refuses until it is cancelled."));
    fill(error);
    delete error.dataset.status;
    dialog.showModal();
  }

  /** @param {JobDetail} job */
  function draw(job) {
    shown = job;
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
