// Small DOM and formatting helpers shared by the pages.

/** h("div.card#id", {attrs, on: {click}}, ...children) — a DOM element. */
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
  for (const [k, v] of Object.entries(attrs)) {
    if (v === undefined || v === null || v === false) continue;
    if (k === "on") for (const [ev, fn] of Object.entries(v)) el.addEventListener(ev, fn);
    else if (k === "dataset") Object.assign(el.dataset, v);
    // through the CSSOM: a style="" attribute is inline style, which the page's
    // Content-Security-Policy refuses (style-src without 'unsafe-inline')
    else if (k === "style") el.style.cssText = v;
    else if (k in el && typeof v !== "string") el[k] = v;
    else el.setAttribute(k, v === true ? "" : v);
  }
  for (const c of children.flat(Infinity)) {
    if (c === undefined || c === null || c === false) continue;
    el.append(c instanceof Node ? c : document.createTextNode(String(c)));
  }
  return el;
}

export function clear(el) { while (el.firstChild) el.removeChild(el.firstChild); return el; }

/** Replace the children of `el` with `children` (null/false skipped). */
export function fill(el, ...children) {
  clear(el);
  for (const c of children.flat(Infinity)) if (c !== null && c !== undefined && c !== false) el.append(c);
  return el;
}

/** A number with 4 significant digits (or "—"). */
export function num(v, digits = 4) {
  if (v === null || v === undefined || Number.isNaN(v)) return "—";
  if (typeof v !== "number") return String(v);
  if (v !== 0 && (Math.abs(v) >= 1e5 || Math.abs(v) < 1e-3)) return v.toExponential(digits - 1);
  return Number(v.toPrecision(digits)).toString();
}

export function best(v) { return Array.isArray(v) ? v.map((x) => num(x)).join(", ") : num(v); }

export function when(iso) {
  if (!iso) return "—";
  const d = new Date(iso);
  return d.toLocaleString(undefined, { dateStyle: "short", timeStyle: "medium" });
}

export function badge(status) { return h(`span.badge.${status}`, status); }

/** One violated constraint with its amount and unit (as the CLI words it). */
export function violationText(v) {
  const size = `${num(v.amount)}${v.unit ? ` ${v.unit}` : ""}`;
  const own = v.text ? ` — ${v.text}` : "";
  return `${v.constraint} over its limit by ${size}${own}`;
}

/** A job's status with its verdict: a succeeded job whose optimum violates a constraint is a
 *  red "infeasible" badge (never the green "succeeded"); one checked feasible is green; one
 *  finished before the service checked says so. */
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

export function bar(fraction, text) {
  const pct = Math.max(0, Math.min(1, fraction || 0)) * 100;
  return h("span", h("span.bar", h("i", { style: `width:${pct.toFixed(1)}%` })), " ", text);
}

export function shortId(id) { return id ? id.slice(0, 8) : ""; }

export function errorBox(err) {
  return h("div.card", h("p.error", err && err.message ? err.message : String(err)));
}

/** Label [unit] of a Quantity from the API. */
export function axis(q) { return q ? q.axis || q.name : ""; }

export const TERMINAL = new Set(["succeeded", "failed", "cancelled"]);
