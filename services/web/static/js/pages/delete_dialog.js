// The Delete confirmation of the job and sweep pages: a dialog that names what is deleted,
// says what goes with it, and on "Delete" sends DELETE to the API. A refusal (409: still
// queued or running, cancel it first; 404: already gone) is shown in the dialog, which stays
// open; once deleted the dialog closes and the page goes to `after` (its list).
import { api, ApiError } from "../api.js";
import { errorText, fill, h } from "../ui.js";

/**
 * @param {{ title: string, note: string, after: string }} what the dialog's heading, what
 *   is removed with it, and the hash to go to once deleted
 * @returns {{ el: HTMLDialogElement, ask: (path: string, message: string) => void }} the
 *   dialog (append it once: a page redraw must not close it) and `ask(path, message)`: open it
 *   for the API path to DELETE, saying `message`
 */
export function deleteDialog({ title, note, after }) {
  const message = h("p#delete-message");
  const error = h("p.error#delete-error");
  const confirmButton = /** @type {HTMLButtonElement} */ (h("button.danger#delete-confirm", "Delete"));
  const dialog = /** @type {HTMLDialogElement} */ (h("dialog#delete-dialog",
    h("h2", title), message, h("p.muted", note), error,
    h("div.toolbar", h("span.spacer"),
      h("button.secondary#delete-cancel", { type: "button", on: { click: () => dialog.close() } }, "Keep it"),
      confirmButton)));
  /** @type {string | null} */
  let asked = null;

  confirmButton.addEventListener("click", async () => {
    if (!asked) return;
    confirmButton.disabled = true;
    fill(error);
    try {
      await api(asked, { method: "DELETE" });
      dialog.close();
      location.hash = after;
    } catch (err) {
      error.dataset.status = err instanceof ApiError ? String(err.status) : "";
      fill(error, errorText(err));
    } finally {
      confirmButton.disabled = false;
    }
  });

  /** @param {string} path @param {string} text */
  function ask(path, text) {
    asked = path;
    fill(message, text);
    fill(error);
    delete error.dataset.status;
    dialog.showModal();
  }

  return { el: dialog, ask };
}
