// The jobs page: filter, sort, search and page your jobs (all done by the API in SQL), watch
// their progress (short polling while any is queued or running), cancel, re-run, submit a new
// job, download the list. A succeeded job whose optimum violates a constraint shows a red
// "infeasible" badge in place of the green "succeeded" (the verdict filter finds them).
import { api, download, idempotencyKey, query } from "../api.js";
import { bar, best, clear, errorText, h, jobBadge, num, shortId, TERMINAL, when } from "../ui.js";

/** @typedef {import("../api_types").DashboardOptions} DashboardOptions */
/** @typedef {import("../api_types").JobDetail} JobDetail */
/** @typedef {import("../api_types").JobRowOut} JobRowOut */
/** @typedef {import("../api_types").JobRowPage} JobRowPage */

const POLL_MS = 2000;
/** @type {Array<[string, string, string | null]>} key, heading, the API's sort key (null: not sortable) */
const COLUMNS = [
  ["name", "job", null], ["kind", "study", "kind"], ["robot", "robot", "robot"],
  ["optimizer", "optimizer", "optimizer"], ["status", "status", "status"],
  ["progress", "progress", "progress"], ["best", "best so far", "best"],
  ["created", "created", "created"], ["finished", "finished", "finished"], ["tags", "tags", null],
  ["actions", "", null],
];

/** The API searches a word shorter than this only next to a longer one (its trigram index
 * answers words of 3 characters or more; a search of short words alone is a 422). */
const MIN_WORD = 3;

/**
 * The search box's text as the API takes it: "" while no word has MIN_WORD characters yet
 * (one or two letters typed so far: the list stays unsearched, the hint shows).
 * @param {string} text
 */
function searchable(text) {
  const words = text.trim().toLowerCase().split(/\s+/).filter(Boolean).slice(0, 8);
  return words.some((w) => [...w].length >= MIN_WORD) ? text.trim() : "";
}

/**
 * The filters, sort and page size a #/jobs?… address asks for.
 * @param {string} hash
 */
function stateFromHash(hash) {
  const q = new URLSearchParams((hash.split("?")[1]) || "");
  return { q: q.get("q") || "", kind: q.get("kind") || "", optimizer: q.get("optimizer") || "",
    robot: q.get("robot") || "", status: q.getAll("status"), sweep_id: q.get("sweep_id") || "",
    feasible: q.get("feasible") || "",
    sort: q.get("sort") || "created", order: q.get("order") || "desc", limit: 50 };
}

/**
 * The jobs page (#/jobs?filters) into `main`; its cleanup.
 * @param {HTMLElement} main
 * @param {string} _param
 * @param {string} hash
 * @returns {Promise<() => void>}
 */
export async function render(main, _param, hash) {
  /** @type {ReturnType<typeof stateFromHash> & { cursors: Array<string | null>, page: number }} */
  const st = { ...stateFromHash(hash), cursors: [null], page: 0 };
  /** @type {DashboardOptions} */
  const options = await api("/dashboard/options");
  /** @type {number | undefined} */
  let timer;
  let alive = true;

  const search = /** @type {HTMLInputElement} */ (h("input#job-search", { type: "search", placeholder: "search name, robot, seed=3, id…", value: st.q, size: 28 }));
  const searchHint = h("span.muted#search-hint", { hidden: true }, `type ${MIN_WORD} or more characters to search`);
  const kind = /** @type {HTMLSelectElement} */ (h("select", h("option", { value: "" }, "all studies"),
    options.kinds.map((k) => h("option", { value: k.value, selected: k.value === st.kind }, k.value))));
  const optimizer = /** @type {HTMLSelectElement} */ (h("select", h("option", { value: "" }, "all optimizers"),
    options.optimizers.map((o) => h("option", { value: o.value, selected: o.value === st.optimizer }, o.label))));
  const robot = /** @type {HTMLInputElement} */ (h("input", { placeholder: "robot", value: st.robot, size: 14 }));
  const verdict = /** @type {HTMLSelectElement} */ (h("select#verdict-filter", h("option", { value: "" }, "any verdict"),
    [["true", "feasible"], ["false", "infeasible"]].map(([v, label]) => h("option", { value: v, selected: v === st.feasible }, label))));
  const statusBoxes = options.statuses.map((s) => h("label", h("input", { type: "checkbox", value: s,
    checked: st.status.includes(s) }), " ", s));
  /** @param {HTMLElement} label a status's label: its checkbox */
  const boxOf = (label) => /** @type {HTMLInputElement} */ (label.firstChild);
  const info = h("span.muted#jobs-count");
  const table = h("table#jobs-table");
  const pager = h("div.pager");

  const filters = () => ({ q: searchable(search.value), kind: kind.value, optimizer: optimizer.value,
    robot: robot.value.trim(), status: statusBoxes.map(boxOf).filter((c) => c.checked).map((c) => c.value),
    sweep_id: st.sweep_id, feasible: verdict.value });

  function restart() { st.cursors = [null]; st.page = 0; load(); }
  for (const el of [kind, optimizer, verdict, ...statusBoxes.map(boxOf)]) el.addEventListener("change", restart);
  /** @type {number | undefined} */
  let debounce;
  const hintSearch = () => { searchHint.hidden = !search.value.trim() || searchable(search.value) !== ""; };
  hintSearch();
  search.addEventListener("input", hintSearch);
  for (const el of [search, robot]) el.addEventListener("input", () => { clearTimeout(debounce); debounce = setTimeout(restart, 300); });

  const newJob = newJobForm(options, () => restart());
  main.append(
    h("div.toolbar", h("h1", "Jobs"), h("span.spacer"),
      h("button.secondary", { on: { click: () => { newJob.hidden = !newJob.hidden; } } }, "New job"),
      ...["csv", "parquet", "json"].map((f) => h("button.secondary", { dataset: { export: f },
        on: { click: () => download(`/export/jobs${query({ ...filters(), format: f })}`, `jobs.${f}`) } }, f.toUpperCase()))),
    newJob,
    h("div.card",
      h("div.toolbar", search, searchHint, kind, optimizer, robot, verdict, ...statusBoxes,
        st.sweep_id ? h("span.tag", `sweep ${shortId(st.sweep_id)}`) : null, h("span.spacer"), info),
      h("div.scroll.full", table), pager));

  async function load() {
    clearTimeout(timer);
    const f = filters();
    const params = { ...f, sort: st.sort, order: st.order, limit: st.limit, cursor: st.cursors[st.page] };
    /** @type {JobRowPage} */
    let page;
    try { page = await api(`/dashboard/jobs${query(params)}`); } catch (err) {
      info.textContent = errorText(err); return;
    }
    if (!alive) return;
    const start = st.page * st.limit;
    // total_exact false: the API stopped counting (total = its cap + 1)
    const total = page.total_exact ? page.total.toLocaleString() : `more than ${(page.total - 1).toLocaleString()}`;
    info.textContent = page.total ? `${start + 1}–${start + page.items.length} of ${total}` : "no jobs";
    drawTable(page.items);
    drawPager(page, start);
    if (page.items.some((j) => !TERMINAL.has(j.status))) timer = setTimeout(load, POLL_MS);
  }

  /** @param {JobRowOut[]} items */
  function drawTable(items) {
    clear(table);
    table.append(h("thead", h("tr", COLUMNS.map(([key, label, sortKey]) => {
      const th = h(`th${sortKey ? ".sortable" : ""}${["progress", "best"].includes(key) ? ".num" : ""}`, label);
      if (sortKey) {
        if (st.sort === sortKey) th.classList.add("sorted", st.order);
        th.addEventListener("click", () => {
          st.order = st.sort === sortKey && st.order === "desc" ? "asc" : "desc";
          st.sort = sortKey;
          restart();
        });
      }
      return th;
    }))));
    const body = h("tbody");
    for (const j of items) {
      const verdictOf = j.feasible === true ? "feasible" : j.feasible === false ? "infeasible" : "";
      const tr = h("tr.clickable", { dataset: { job: j.id, status: j.status, verdict: verdictOf } },
        h("td", h("a", { href: `#/job/${j.id}` }, j.name || shortId(j.id)), j.name ? h("div.muted.mono", shortId(j.id)) : null),
        h("td", j.kind), h("td", j.robot), h("td", j.optimizer), h("td", jobBadge(j)),
        h("td", bar(j.progress, `${j.generation}/${j.total_generations || "?"}`)),
        h("td.num.best", j.best_named.length
          ? j.best_named.map((q) => h("div", { title: q.label }, `${q.name} ${num(q.value)}${q.unit ? ` ${q.unit}` : ""}`))
          : best(j.best_objective)), h("td", when(j.created_at)), h("td", when(j.finished_at)),
        h("td", j.tags.map((t) => h("span.tag", t)), j.sweep_id ? h("a.tag", { href: `#/sweep/${j.sweep_id}` }, "sweep") : null),
        h("td", actions(j)));
      tr.addEventListener("click", (ev) => {
        if (!/** @type {Element} */ (ev.target).closest("a,button")) location.hash = `#/job/${j.id}`;
      });
      body.append(tr);
    }
    table.append(body);
  }

  /**
   * The buttons of a job's row: cancel (unless finished), re-run.
   * @param {JobRowOut} j
   */
  function actions(j) {
    const out = [];
    if (!TERMINAL.has(j.status)) {
      out.push(h("button.danger", { title: "Cancel this job", dataset: { action: "cancel" }, on: { click: async (ev) => {
        /** @type {HTMLButtonElement} */ (ev.target).disabled = true;
        try { await api(`/jobs/${j.id}/cancel`, { method: "POST" }); } catch (err) { info.textContent = errorText(err); }
        load(); } } }, "Cancel"));
    }
    out.push(h("button.secondary", { title: "Submit the same spec with a new seed", dataset: { action: "rerun" }, on: { click: async (ev) => {
      const button = /** @type {HTMLButtonElement} */ (ev.target);
      button.disabled = true;
      let created;
      try { created = await rerun(j.id); } catch (err) { info.textContent = errorText(err); button.disabled = false; return; }
      location.hash = `#/job/${created.id}`;
    } } }, "Re-run"));
    return out;
  }

  /**
   * @param {JobRowPage} page
   * @param {number} start the index of the page's first row
   */
  function drawPager(page, start) {
    clear(pager);
    const prev = h("button.secondary", { disabled: start === 0, on: { click: () => {
      st.page -= 1; load(); } } }, "← previous");
    const next = h("button.secondary", { disabled: page.next_cursor === null, on: { click: () => {
      st.cursors[st.page + 1] = page.next_cursor; st.page += 1; load(); } } }, "next →");
    pager.append(prev, next, h("span.muted", `page ${st.page + 1}`));
  }

  await load();
  return () => { alive = false; clearTimeout(timer); };
}

/**
 * Submit a job's spec again with a new seed; the new job.
 * @param {string} jobId
 * @returns {Promise<JobDetail>}
 */
export async function rerun(jobId) {
  /** @type {JobDetail} */
  const job = await api(`/jobs/${jobId}`);
  const spec = { ...job.spec, seed: Math.floor(Math.random() * 2 ** 31) };
  return api("/jobs", { method: "POST", body: spec, headers: { "Idempotency-Key": idempotencyKey() } });
}

/**
 * The "New job" form: a study with the paper's defaults, or a pasted spec.
 * @param {DashboardOptions} options
 * @param {(job: JobDetail) => void} onDone called with the job submitted
 * @returns {HTMLElement}
 */
function newJobForm(options, onDone) {
  const kind = /** @type {HTMLSelectElement} */ (h("select#new-kind", options.kinds.map((k) => h("option", { value: k.value }, `${k.value} — ${k.label}`))));
  const generations = /** @type {HTMLInputElement} */ (h("input#new-generations", { type: "number", min: 1, value: 10, size: 6 }));
  const text = /** @type {HTMLTextAreaElement} */ (h("textarea#new-spec", { rows: 6, cols: 80, placeholder: '{"problem": {"kind": "path_tracking"}, "budget": {"generations": 20}}' }));
  const msg = h("p.muted");
  const form = h("div.card#new-job", { hidden: true },
    h("h2", "New job"),
    h("div.toolbar", "Study (the seed paper's defaults)", kind, "generations", generations,
      h("button#submit-example", { on: { click: () => submit({ problem: { kind: kind.value }, budget: { generations: Number(generations.value) } }) } }, "Submit")),
    h("p.muted", "…or paste a whole job spec (JSON, the document of `legopt run`):"), text,
    h("div.toolbar", h("button.secondary", { on: { click: () => {
      try { submit(JSON.parse(text.value)); } catch (err) { msg.textContent = `not JSON: ${errorText(err)}`; }
    } } }, "Submit spec")), msg);
  /** @param {unknown} spec a job spec (the document of `legopt run`) */
  async function submit(spec) {
    msg.textContent = "submitting…";
    try {
      /** @type {JobDetail} */
      const job = await api("/jobs", { method: "POST", body: spec, headers: { "Idempotency-Key": idempotencyKey() } });
      msg.textContent = `job ${job.id} queued`;
      onDone(job);
    } catch (err) { msg.textContent = errorText(err); msg.className = "error"; }
  }
  return form;
}
