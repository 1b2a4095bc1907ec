// The API client of the dashboard: the key the user logged in with (session storage), JSON
// requests with the X-API-Key header, and downloads (fetched with the key, saved from a blob).

/**
 * The options of api(): `body` is sent as JSON; `raw` answers the Response itself.
 * @typedef {{ method?: string, body?: unknown, raw?: boolean, headers?: Record<string, string> }} ApiOptions
 */

export const API = "/api/v1";
const STORE = "legopt.apiKey";

/** @returns {string} the key the user logged in with ("" when none) */
export function getKey() { return sessionStorage.getItem(STORE) || ""; }
/** @param {string} key */
export function setKey(key) { sessionStorage.setItem(STORE, key); }
export function clearKey() { sessionStorage.removeItem(STORE); }

/** An answer of the API that is not 2xx: its status and `detail` (a message, or 422's list). */
export class ApiError extends Error {
  /**
   * @param {number} status
   * @param {unknown} detail
   */
  constructor(status, detail) {
    super(typeof detail === "string" ? detail : ApiError.format(detail));
    this.status = status;
    this.detail = detail;
  }
  /**
   * @param {unknown} detail
   * @returns {string}
   */
  static format(detail) {
    if (Array.isArray(detail)) {
      return detail.map((e) => `${(e.loc || []).join(".")}: ${e.msg}`).join("; ");
    }
    return JSON.stringify(detail);
  }
}

/** @type {(detail: unknown) => void} */
let onUnauthorized = () => {};
/** @param {(detail: unknown) => void} fn called on 401 with the API's detail */
export function whenUnauthorized(fn) { onUnauthorized = fn; }

/**
 * fetch(API + path) with the key; JSON in and out; throws ApiError (401 → log in again).
 * The JSON answer is of the type the caller declares for it (a type of ./api_types, from the
 * API's OpenAPI document); undeclared, it is `unknown`.
 * @overload
 * @param {string} path
 * @param {ApiOptions & { raw: true }} options
 * @returns {Promise<Response>}
 */
/**
 * @template [T=unknown]
 * @overload
 * @param {string} path
 * @param {ApiOptions & { raw?: false }} [options]
 * @returns {Promise<T>} the JSON answer (null for 204)
 */
/**
 * @param {string} path
 * @param {ApiOptions} [options]
 * @returns {Promise<unknown>}
 */
export async function api(path, { method = "GET", body, raw = false, headers = {} } = {}) {
  /** @type {RequestInit & { headers: Record<string, string> }} */
  const init = { method, headers: { "X-API-Key": getKey(), ...headers } };
  if (body !== undefined) {
    init.body = JSON.stringify(body);
    init.headers["Content-Type"] = "application/json";
  }
  const res = await fetch(API + path, init);
  if (!res.ok) {
    let detail = res.statusText;
    try { detail = (await res.json()).detail ?? detail; } catch (_) { /* not JSON */ }
    if (res.status === 401) onUnauthorized(detail);
    throw new ApiError(res.status, detail);
  }
  if (raw) return res;
  if (res.status === 204) return null;
  return res.json();
}

/**
 * The bytes of an API resource (retried while the server answers 503 + Retry-After).
 * @param {string} path
 * @param {{ tries?: number }} [options]
 * @returns {Promise<ArrayBuffer>}
 */
export async function apiBytes(path, { tries = 12 } = {}) {
  for (let i = 0; ; i++) {
    try {
      const res = await api(path, { raw: true });
      return await res.arrayBuffer();
    } catch (err) {
      if (!(err instanceof ApiError) || err.status !== 503 || i >= tries) throw err;
      await new Promise((r) => setTimeout(r, 2500));
    }
  }
}

/**
 * Download an API resource as a file named by its Content-Disposition (or `fallback`).
 * @param {string} path
 * @param {string} fallback
 * @returns {Promise<void>}
 */
export async function download(path, fallback) {
  const res = await api(path, { raw: true });
  const blob = await res.blob();
  const cd = res.headers.get("Content-Disposition") || "";
  const m = /filename="?([^";]+)"?/.exec(cd);
  const a = document.createElement("a");
  a.href = URL.createObjectURL(blob);
  a.download = m ? m[1] : fallback;
  document.body.appendChild(a);
  a.click();
  setTimeout(() => { URL.revokeObjectURL(a.href); a.remove(); }, 1000);
}

/**
 * "?a=1&b=2&b=3" from an object (arrays repeat, empty values dropped; "" when none).
 * @param {Record<string, string | number | boolean | null | undefined | Array<string | number>>} params
 * @returns {string}
 */
export function query(params) {
  const q = new URLSearchParams();
  for (const [k, v] of Object.entries(params)) {
    if (v === undefined || v === null || v === "") continue;
    for (const item of Array.isArray(v) ? v : [v]) q.append(k, String(item));
  }
  const s = q.toString();
  return s ? `?${s}` : "";
}

/** @returns {string} a fresh Idempotency-Key (a retried submission creates one job) */
export function idempotencyKey() {
  if (window.crypto && crypto.randomUUID) return crypto.randomUUID();
  return `${Date.now()}-${Math.random().toString(16).slice(2)}`;
}

/**
 * Follow a Server-Sent Events stream of the API (fetched with the key, which EventSource
 * cannot send): `onEvent(name, data)` per event; resolves when the stream ends (the server
 * closed it, or `signal` aborted it); rejects when it cannot be opened or breaks.
 * @param {string} path
 * @param {(name: string, data: unknown) => void} onEvent
 * @param {AbortSignal} signal
 * @returns {Promise<void>}
 */
export async function follow(path, onEvent, signal) {
  const res = await fetch(API + path, { headers: { "X-API-Key": getKey(), Accept: "text/event-stream" }, signal });
  if (!res.ok || !res.body) throw new ApiError(res.status, res.statusText);
  const reader = res.body.pipeThrough(new TextDecoderStream()).getReader();
  let buffer = "";
  for (;;) {
    const { value, done } = await reader.read();
    if (done) return;
    buffer += value;
    let cut;
    while ((cut = buffer.indexOf("\n\n")) >= 0) {
      const block = buffer.slice(0, cut);
      buffer = buffer.slice(cut + 2);
      let name = "message";
      const data = [];
      for (const line of block.split("\n")) {
        if (line.startsWith("event:")) name = line.slice(6).trim();
        else if (line.startsWith("data:")) data.push(line.slice(5).trimStart());
      }
      if (data.length) {
        let parsed = null;
        try { parsed = JSON.parse(data.join("\n")); } catch (_) { parsed = data.join("\n"); }
        onEvent(name, parsed);
      }
    }
  }
}
