// Keeping a page current: it follows a Server-Sent Events stream of the API (GET
// /jobs/{id}/events, /sweeps/{id}/events) and redraws on each pushed event, within a second of
// the change; where the stream cannot be opened (429: too many streams on the server; a proxy
// that buffers) or breaks, it polls instead. While it streams, a slow poll runs only in case.
import { follow } from "./api.js";

/**
 * @typedef {object} LiveOptions
 * @property {number} pollMs how often to refresh when there is no stream
 * @property {number} [safetyMs] how often to refresh while the stream is open
 * @property {(name: string, data: unknown) => void} [onEvent] each pushed event, as it arrives
 *   (before the refresh it causes)
 */

/**
 * Follow `path` and run `refresh()` on each event, one refresh at a time (events that arrive
 * meanwhile make one more). `refresh()` answers whether the thing followed is finished: then
 * the stream and the polls stop. `first()` runs the first refresh (its error is thrown) and
 * starts following; `refresh()` asks for one now (e.g. after a button changed the thing);
 * `stop()` ends everything (the page's cleanup).
 * @param {string} path
 * @param {() => Promise<boolean>} refresh
 * @param {LiveOptions} options
 * @returns {{ first: () => Promise<void>, refresh: () => void, stop: () => void, streaming: () => boolean }}
 */
export function keepCurrent(path, refresh, { pollMs, safetyMs = 15000, onEvent }) {
  const stream = new AbortController();
  let alive = true;
  let streaming = false;
  let failed = false;
  let finished = false;
  // the last event said the thing is finished (or gone): the server ends the stream after it
  let ended = false;
  let running = false;
  let again = false;
  /** @type {number | undefined} */
  let timer;

  function startStream() {
    if (streaming || failed || finished || !alive) return;
    streaming = true;
    follow(path, (name, data) => {
      if (onEvent) onEvent(name, data);
      if (name === "gone" || (data && typeof data === "object" && "terminal" in data && data.terminal === true)) ended = true;
      if (name === "progress" || name === "gone") soon();
    }, stream.signal)
      // the server ends a stream after the last event, or after its time limit: open another
      .then(() => { streaming = false; if (alive && !finished && !ended) startStream(); })
      .catch(() => { streaming = false; if (stream.signal.aborted) return; failed = true; if (alive) soon(); });
  }

  /** @param {boolean} done what the refresh answered */
  function schedule(done) {
    finished = finished || done;
    clearTimeout(timer);
    if (!alive) return;
    if (finished) { stream.abort(); return; }
    startStream();
    timer = setTimeout(soon, streaming ? safetyMs : pollMs);
  }

  function soon() {
    if (!alive) return;
    if (running) { again = true; return; }
    running = true;
    clearTimeout(timer);
    refresh().then(schedule, () => schedule(false)).finally(() => {
      running = false;
      if (again && alive && !finished) { again = false; soon(); }
    });
  }

  async function first() {
    running = true;
    try {
      schedule(await refresh());
    } finally {
      running = false;
    }
    if (again && alive && !finished) { again = false; soon(); }
  }

  return {
    first,
    refresh: soon,
    stop() { alive = false; stream.abort(); clearTimeout(timer); },
    streaming: () => streaming,
  };
}
