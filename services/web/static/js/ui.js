// Small DOM and formatting helpers shared by the pages.

/** @typedef {import("./api_types").JobOut} JobOut */
/** @typedef {import("./api_types").ViolationOut} ViolationOut */

/**
 * What h() appends: nodes, text (strings, numbers), nested lists; null, undefined and false
 * are skipped.
 * @typedef {Node | string | number | boolean | null | undefined | ChildList} Child
 */
/** @typedef {Child[]} ChildList */
/**
 * The attributes of h(): `on` (event listeners), `dataset`, `style` (CSS text, set through the
 * CSSOM), element properties (non-string values of names the element has) and attributes
 * (true: present; null, undefined and false: absent).
 * @typedef {{ on?: Record<string, (ev: Event) => unknown>, dataset?: Record<string, string | number | boolean>,
 *   style?: string, [name: string]: unknown }} Attrs
 */

/**
 * h("div.card#id", {attrs, on: {click}}, ...children) — a DOM element (an HTMLElement: cast it
 * where its own type matters, e.g. an input's value).
 * @param {string} spec tag, .classes and #id
 * @param {Attrs | Child} [attrs] attributes, or the first child
 * @param {...Child} children
 * @returns {HTMLElement}
 */
export function h(spec, attrs = {}, ...children) {
  const [tagAndClasses, id] = spec.split("#");
  const [tag, ...classes] = tagAndClasses.split(".");
  const el = document.createElement(tag || "div");
  if (classes.length) el.className = classes.join(" ");
  if (id) el.id = id;
  if (attrs === null || attrs === undefined || attrs instanceof Node
      || typeof attrs !== "object" || Array.isArray(attrs)) {
    if (attrs !== null && attrs !== undefined) children.unshift(attrs);
    attrs = {};
  }
  const props = /** @type {Record<string, unknown>} */ (/** @type {unknown} */ (el));
  for (const [k, v] of Object.entries(/** @type {Attrs} */ (attrs))) {
    if (v === undefined || v === null || v === false) continue;
    if (k === "on") for (const [ev, fn] of Object.entries(/** @type {Record<string, EventListener>} */ (v))) el.addEventListener(ev, fn);
    else if (k === "dataset") Object.assign(el.dataset, v);
    // through the CSSOM: a style="" attribute is inline style, which the page's
    // Content-Security-Policy refuses (style-src without 'unsafe-inline')
    else if (k === "style") el.style.cssText = String(v);
    else if (k in el && typeof v !== "string") props[k] = v;
    else el.setAttribute(k, v === true ? "" : String(v));
  }
  for (const c of /** @type {unknown[]} */ (children).flat(Infinity)) {
    if (c === undefined || c === null || c === false) continue;
    el.append(c instanceof Node ? c : document.createTextNode(String(c)));
  }
  return el;
}

/**
 * Remove the children of `el`.
 * @template {Node} E
 * @param {E} el
 * @returns {E}
 */
export function clear(el) { while (el.firstChild) el.removeChild(el.firstChild); return el; }

/**
 * Replace the children of `el` with `children` (null/false skipped).
 * @template {Element} E
 * @param {E} el
 * @param {...(Node | string | null | undefined | false | ChildList)} children
 * @returns {E}
 */
export function fill(el, ...children) {
  clear(el);
  for (const c of /** @type {unknown[]} */ (children).flat(Infinity)) {
    if (c !== null && c !== undefined && c !== false) el.append(/** @type {Node | string} */ (c));
  }
  return el;
}

/**
 * A number with 4 significant digits (or "—").
 * @param {unknown} v
 * @param {number} [digits]
 * @returns {string}
 */
export function num(v, digits = 4) {
  if (v === null || v === undefined || Number.isNaN(v)) return "—";
  if (typeof v !== "number") return String(v);
  if (v !== 0 && (Math.abs(v) >= 1e5 || Math.abs(v) < 1e-3)) return v.toExponential(digits - 1);
  return Number(v.toPrecision(digits)).toString();
}

/**
 * An objective value or vector (a job's best so far).
 * @param {unknown} v
 * @returns {string}
 */
export function best(v) { return Array.isArray(v) ? v.map((x) => num(x)).join(", ") : num(v); }

/**
 * A date and time (ISO 8601 from the API) in the browser's locale, or "—".
 * @param {string | null | undefined} iso
 * @returns {string}
 */
export function when(iso) {
  if (!iso) return "—";
  const d = new Date(iso);
  return d.toLocaleString(undefined, { dateStyle: "short", timeStyle: "medium" });
}

/**
 * @param {string} status
 * @returns {HTMLElement}
 */
export function badge(status) { return h(`span.badge.${status}`, status); }

/**
 * One violated constraint with its amount and unit (as the CLI words it).
 * @param {ViolationOut} v
 * @returns {string}
 */
export function violationText(v) {
  const size = `${num(v.amount)}${v.unit ? ` ${v.unit}` : ""}`;
  const own = v.text ? ` — ${v.text}` : "";
  return `${v.constraint} over its limit by ${size}${own}`;
}

/** A job's status with its verdict: a succeeded job whose optimum violates a constraint is a
 *  red "infeasible" badge (never the green "succeeded"); one checked feasible is green; one
 *  finished before the service checked says so.
 * @param {Pick<JobOut, "status" | "feasible" | "violations">} job a job or a row of the jobs page
 * @returns {HTMLElement}
 */
export function jobBadge(job) {
  if (job.status !== "succeeded") return badge(job.status);
  if (job.feasible === false) {
    const why = (job.violations || []).map(violationText).join("; ");
    return h("span.badge.infeasible", { title: `succeeded, but the optimum is infeasible: ${why}`,
      dataset: { verdict: "infeasible" } }, "infeasible");
  }
  if (job.feasible === true) {
    return h("span.badge.succeeded", { title: "the optimum meets every constraint",
      dataset: { verdict: "feasible" } }, "succeeded");
  }
  return h("span.badge.unchecked", { title: "feasibility not checked (finished before the service checked it)",
    dataset: { verdict: "unchecked" } }, "succeeded");
}

/**
 * A progress bar of `fraction` (0…1) and its text.
 * @param {number | null | undefined} fraction
 * @param {string} text
 * @returns {HTMLElement}
 */
export function bar(fraction, text) {
  const pct = Math.max(0, Math.min(1, fraction || 0)) * 100;
  return h("span", h("span.bar", h("i", { style: `width:${pct.toFixed(1)}%` })), " ", text);
}

/**
 * The first 8 characters of an id.
 * @param {string | null | undefined} id
 * @returns {string}
 */
export function shortId(id) { return id ? id.slice(0, 8) : ""; }

/**
 * What went wrong, in words: an error's message (or the thrown value as text).
 * @param {unknown} err
 * @returns {string}
 */
export function errorText(err) { return err instanceof Error ? err.message : String(err); }

/**
 * @param {unknown} err
 * @returns {HTMLElement}
 */
export function errorBox(err) {
  return h("div.card", h("p.error", err instanceof Error && err.message ? err.message : String(err)));
}

/**
 * Label [unit] of a Quantity from the API.
 * @param {{ name: string, axis?: string } | null | undefined} q
 * @returns {string}
 */
export function axis(q) { return q ? q.axis || q.name : ""; }

/** The statuses a job does not leave. */
export const TERMINAL = new Set(["succeeded", "failed", "cancelled"]);
