// Your sweeps, newest first, with their job counts.
import { api, query } from "../api.js";
import { badge, fill, h, shortId, when } from "../ui.js";

/** @typedef {import("../api_types").Page_SweepSummary} SweepPage */

/**
 * The sweeps page (#/sweeps) into `main`.
 * @param {HTMLElement} main
 * @returns {Promise<void>}
 */
export async function render(main) {
  const table = h("table#sweeps-table");
  const pager = h("div.pager");
  let offset = 0;
  const limit = 50;
  main.append(h("h1", "Sweeps"), h("div.card", table, pager));

  async function load() {
    /** @type {SweepPage} */
    const page = await api(`/sweeps${query({ limit, offset })}`);
    fill(table, h("thead", h("tr", h("th", "sweep"), h("th", "created"), h("th.num", "jobs"),
      h("th", "state"), h("th", "statuses"))));
    const body = h("tbody");
    for (const s of page.items) {
      const counts = Object.entries(s.counts).filter(([, n]) => n).map(([k, n]) => h("span", badge(k), ` ${n} `));
      const tr = h("tr.clickable", { dataset: { sweep: s.id } }, h("td", h("a", { href: `#/sweep/${s.id}` }, shortId(s.id))),
        h("td", when(s.created_at)), h("td.num", String(s.n_jobs)), h("td", s.state), h("td", counts));
      tr.addEventListener("click", () => { location.hash = `#/sweep/${s.id}`; });
      body.append(tr);
    }
    if (!page.items.length) body.append(h("tr", h("td", { colspan: 5 }, h("span.muted", "No sweeps yet: `legopt sweep FILE` or POST /api/v1/sweeps."))));
    table.append(body);
    fill(pager, 
      h("button.secondary", { disabled: offset === 0, on: { click: () => { offset -= limit; load(); } } }, "← newer"),
      h("button.secondary", { disabled: offset + limit >= page.total, on: { click: () => { offset += limit; load(); } } }, "older →"),
      h("span.muted", `${page.total} sweeps`));
  }
  await load();
}
