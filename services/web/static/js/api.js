// The API client of the dashboard: the key the user logged in with (session storage), JSON
// requests with the X-API-Key header, and downloads (fetched with the key, saved from a blob).

export const API = "/api/v1";
const STORE = "legopt.apiKey";

export function getKey() { return sessionStorage.getItem(STORE) || ""; }
export function setKey(key) { sessionStorage.setItem(STORE, key); }
export function clearKey() { sessionStorage.removeItem(STORE); }

export class ApiError extends Error {
  constructor(status, detail) {
    super(typeof detail === "string" ? detail : ApiError.format(detail));
    this.status = status;
    this.detail = detail;
  }
  static format(detail) {
    if (Array.isArray(detail)) {
      return detail.map((e) => `${(e.loc || []).join(".")}: ${e.msg}`).join("; ");
    }
    return JSON.stringify(detail);
  }
}

let onUnauthorized = () => {};
export function whenUnauthorized(fn) { onUnauthorized = fn; }

/** fetch(API + path) with the key; JSON in and out; throws ApiError (401 → log in again). */
export async function api(path, { method = "GET", body, raw = false, headers = {} } = {}) {
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

/** The bytes of an API resource (retried while the server answers 503 + Retry-After). */
export async function apiBytes(path, { tries = 12 } = {}) {
  for (let i = 0; ; i++) {
    try {
      const res = await api(path, { raw: true });
      return await res.arrayBuffer();
    } catch (err) {
      if (err.status !== 503 || i >= tries) throw err;
      await new Promise((r) => setTimeout(r, 2500));
    }
  }
}

/** Download an API resource as a file named by its Content-Disposition (or `fallback`). */
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

/** "a=1&b=2&b=3" from an object (arrays repeat, empty values dropped). */
export function query(params) {
  const q = new URLSearchParams();
  for (const [k, v] of Object.entries(params)) {
    if (v === undefined || v === null || v === "") continue;
    for (const item of Array.isArray(v) ? v : [v]) q.append(k, item);
  }
  const s = q.toString();
  return s ? `?${s}` : "";
}

/** A fresh Idempotency-Key (a retried submission creates one job). */
export function idempotencyKey() {
  if (window.crypto && crypto.randomUUID) return crypto.randomUUID();
  return `${Date.now()}-${Math.random().toString(16).slice(2)}`;
}
