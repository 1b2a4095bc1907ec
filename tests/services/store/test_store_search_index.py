"""The jobs page's word search reads an index (issue 23, item 3): an FTS5 trigram table on
SQLite, a pg_trgm GIN index on PostgreSQL (revision 0009; ``create_all`` makes them too).

Search by the index finds exactly what the LIKE scan it replaces finds — every word, short
words (which no trigram answers: still LIKE), LIKE's own wildcard characters, quotes, case, other
filters, every order, keyset and offset pages, a word in more matches than are counted; and a
word shaped like a job or sweep id, answered by the primary key and the sweep index (the same
rows, on both stores — but a name that contains an id is not found by it). The index itself
(its table follows the labels, the plans read it, stores without it):
``test_store_search_plumbing``."""

from __future__ import annotations

from typing import Any

import pytest
from search_jobs import N, _fill, _fill_sweep, _ids, _texts
from sqlalchemy import Engine, update
from sqlalchemy.orm import Session, sessionmaker

from services.store import api_keys
from services.store import dashboard_queries as dq
from services.store.states import JobStatus
from services.store.tables import JOB_LABELS

#: What a user types: words of every length, LIKE's wildcards, quotes, case, several words.
QUERIES = [
    "seed=1", "seed=12", "SEED=3", "calderon", "100%_", "%", "_", "a_b", "a%b", '"this"', '"',
    "back\\slash", "\\", "ünï", "straße", "sweep wide", "ab", "a", "nsga2 seed=2", "ga", "demo",
    "energy-time ci", "path_tracking", "zzz", "leg 100", "e", "gait demo", "t", "it's", "'",
    "'test'", "a' OR '1'='1",
]  # fmt: skip


def _walk(s: Session, key_id: str, f: dq.JobFilter, **kw: Any) -> list[str]:
    """Every id of a listing, page by page (keyset cursor)."""
    out: list[str] = []
    cursor = None
    while True:
        page = dq.list_job_rows(s, key_id, f, limit=3, cursor=cursor, count=False, **kw)
        out += _ids(page)
        cursor = page.next_cursor
        if cursor is None:
            return out


@pytest.fixture
def filled(engine: Engine) -> tuple[sessionmaker[Session], str]:
    """A key with N jobs, and another key with N jobs the first must never find."""
    factory = sessionmaker(engine)
    with factory.begin() as s:
        key_id = api_keys.create_api_key(s, name="search", key_hash="s" * 64).id
        other = api_keys.create_api_key(s, name="other", key_hash="o" * 64).id
        _fill(s, key_id)
        _fill(s, other, start=N)
    return factory, key_id


def _same_as_the_scan(s: Session, key_id: str, texts: dict[str, str], q: str) -> dq.JobRowPage:
    """The indexed search ``q``'s first page: its rows those whose text holds every word, the
    same rows, order and total as the LIKE scan's."""
    words = q.lower().split()
    want = {j for j, t in texts.items() if all(w in t for w in words)}
    f = dq.JobFilter(search=q)
    page = dq.list_job_rows(s, key_id, f, limit=100)
    scan = dq.list_job_rows(s, key_id, f, limit=100, search_index=False)
    assert set(_ids(page)) == want, q
    assert _ids(page) == _ids(scan) and page.total == scan.total == len(want), q
    return page


def test_search_finds_what_the_like_scan_finds(filled: tuple[sessionmaker[Session], str]) -> None:
    factory, key_id = filled
    with factory() as s:
        texts = _texts(s, key_id)
        assert len(texts) == N
        for q in QUERIES:
            _same_as_the_scan(s, key_id, texts, q)
        assert dq.list_job_rows(s, key_id, dq.JobFilter(search="calderon")).total > 0


@pytest.mark.parametrize("sort", ["created", "best", "kind", "status"])
def test_search_with_filters_orders_and_pages(
    filled: tuple[sessionmaker[Session], str], sort: str
) -> None:
    factory, key_id = filled
    filters = [
        dq.JobFilter(search="seed=1"),
        dq.JobFilter(search="demo seed", status=(JobStatus.SUCCEEDED, JobStatus.QUEUED)),
        dq.JobFilter(search="nsga2", kind="swing_energy"),
        dq.JobFilter(search="leg a", tag="demo"),
    ]
    with factory() as s:
        for f in filters:
            for descending in (True, False):
                kw: dict[str, Any] = {"sort": sort, "descending": descending}
                scan = _ids(dq.list_job_rows(s, key_id, f, limit=100, search_index=False, **kw))
                assert scan, f
                assert _walk(s, key_id, f, **kw) == scan, (f, kw)
                by_offset = [
                    i
                    for offset in range(0, len(scan), 4)
                    for i in _ids(dq.list_job_rows(s, key_id, f, limit=4, offset=offset, **kw))
                ]
                assert by_offset == scan, (f, kw)


def test_a_word_in_more_jobs_than_counted_is_read_the_old_way(
    filled: tuple[sessionmaker[Session], str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """More matches than COUNT_CAP: the total says "more than", the page walks the order."""
    factory, key_id = filled
    monkeypatch.setattr(dq, "COUNT_CAP", 5)
    with factory() as s:
        for q in ("seed", "nsga2", "seed=1", "seed=12", "seed=12 ga"):
            scan = dq.list_job_rows(s, key_id, dq.JobFilter(search=q), search_index=False)
            page = dq.list_job_rows(s, key_id, dq.JobFilter(search=q))
            assert page.total == scan.total and _ids(page) == _ids(scan), q
            assert _walk(s, key_id, dq.JobFilter(search=q)) == _walk(
                s, key_id, dq.JobFilter(search=q), search_index=False
            )
        assert dq.list_job_rows(s, key_id, dq.JobFilter(search="nsga2")).total == 6


@pytest.fixture
def swept(
    filled: tuple[sessionmaker[Session], str], engine: Engine
) -> tuple[sessionmaker[Session], str, dict[str, str]]:
    """``filled`` with a sweep of 5 jobs for the key and one for the other key; the ids the
    id-word tests search: ``job``, ``sweep`` (the key's), ``sweep_job``, ``other_job`` and
    ``other_sweep`` (the other key's)."""
    factory, key_id = filled
    with factory.begin() as s:
        sweep, sweep_jobs = _fill_sweep(s, key_id)
        other_key = api_keys.create_api_key(s, name="third", key_hash="t" * 64).id
        other_sweep, other_jobs = _fill_sweep(s, other_key, n=2)
    with factory() as s:
        job = sorted(_texts(s, key_id))[7]
    ids = {"job": job, "sweep": sweep, "sweep_job": sweep_jobs[2], "other_job": other_jobs[0],
           "other_sweep": other_sweep}  # fmt: skip
    return factory, key_id, ids


def _id_queries(ids: dict[str, str]) -> list[str]:
    """Searches with words shaped like ids: whole, upper-cased, prefixes through the first
    dash and longer, with other words (long and short), two ids, ids of nobody / another key;
    and the 8-digit short id (trigrams, not an id word)."""
    job, sweep, sweep_job = ids["job"], ids["sweep"], ids["sweep_job"]
    return [
        job, job.upper(), job[:9], job[:13], job[:24], job[:30], sweep, sweep[:9], sweep_job,
        sweep_job[:14], f"{job} seed", f"{job} ga", f"{job[:9]} zzz", f"nsga2 {sweep}",
        f"{sweep} seed=3", f"{sweep} {sweep_job}", f"{sweep_job} {job}", f"{sweep} a",
        ids["other_job"], ids["other_sweep"], "00000000-0000-4000-8000-000000000000",
        "ffffffff-", job[:8], sweep[:8],
    ]  # fmt: skip


def test_an_id_word_finds_what_the_like_scan_finds(
    swept: tuple[sessionmaker[Session], str, dict[str, str]],
) -> None:
    factory, key_id, ids = swept
    with factory() as s:
        texts = _texts(s, key_id)
        for q in _id_queries(ids):
            assert _same_as_the_scan(s, key_id, texts, q).total_exact, q
        assert len(_ids(dq.list_job_rows(s, key_id, dq.JobFilter(search=ids["sweep"])))) == 5
        assert _ids(dq.list_job_rows(s, key_id, dq.JobFilter(search=ids["job"]))) == [ids["job"]]


@pytest.mark.parametrize("sort", ["created", "best", "kind", "status"])
def test_an_id_word_with_filters_orders_and_pages(
    swept: tuple[sessionmaker[Session], str, dict[str, str]], sort: str
) -> None:
    factory, key_id, ids = swept
    sweep = ids["sweep"]
    filters = [
        dq.JobFilter(search=sweep),
        dq.JobFilter(search=sweep[:9]),
        dq.JobFilter(search=f"{sweep} seed", status=(JobStatus.QUEUED,)),
        dq.JobFilter(search=sweep, kind="path_tracking", tag="demo"),
        dq.JobFilter(search=f"{sweep} nsga2", sweep_id=sweep),
        dq.JobFilter(search=ids["job"], tag="demo"),
        dq.JobFilter(search=ids["job"], feasible=True),
    ]
    with factory() as s:
        for f in filters:
            for descending in (True, False):
                kw: dict[str, Any] = {"sort": sort, "descending": descending}
                scan = dq.list_job_rows(s, key_id, f, limit=100, search_index=False, **kw)
                page = dq.list_job_rows(s, key_id, f, limit=100, **kw)
                assert _ids(page) == _ids(scan) and page.total == scan.total, (f, kw)
                assert _walk(s, key_id, f, **kw) == _ids(scan), (f, kw)
                by_offset = [
                    i
                    for offset in range(0, max(1, len(_ids(scan))), 2)
                    for i in _ids(dq.list_job_rows(s, key_id, f, limit=2, offset=offset, **kw))
                ]
                assert by_offset == _ids(scan), (f, kw)


def test_an_id_word_is_counted_up_to_the_cap_and_still_sorted(
    swept: tuple[sessionmaker[Session], str, dict[str, str]], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A sweep's id matches more jobs than the count's cap: "more than", and the page the
    same rows in the same order as the LIKE scan."""
    factory, key_id, ids = swept
    monkeypatch.setattr(dq, "COUNT_CAP", 3)
    with factory() as s:
        f = dq.JobFilter(search=ids["sweep"])
        page = dq.list_job_rows(s, key_id, f, limit=2)
        scan = dq.list_job_rows(s, key_id, f, limit=2, search_index=False)
        assert page.total == scan.total == 4 and not page.total_exact
        assert _ids(page) == _ids(scan)
        assert _walk(s, key_id, f) == _walk(s, key_id, f, search_index=False)
        assert len(_walk(s, key_id, f)) == 5


def test_an_id_word_finds_ids_not_names_containing_one(
    swept: tuple[sessionmaker[Session], str, dict[str, str]],
) -> None:
    """The one place an id word differs from LIKE: a job whose name (or tags, robot) contains
    another job's id is not found by that id; and a word is still checked on the label's text
    (a job's own text without its id — never written so — is not found by it)."""
    factory, key_id, ids = swept
    job, named = ids["job"], ids["sweep_job"]
    with factory.begin() as s:
        s.execute(
            update(JOB_LABELS)
            .where(JOB_LABELS.c.job_id == named)
            .values(search=f"rerun of {job} path_tracking")
        )
    with factory() as s:
        f = dq.JobFilter(search=job)
        assert _ids(dq.list_job_rows(s, key_id, f)) == [job]
        assert set(_ids(dq.list_job_rows(s, key_id, f, search_index=False))) == {job, named}
        assert _ids(dq.list_job_rows(s, key_id, dq.JobFilter(search=named))) == []


def test_a_search_of_short_words_only_is_unindexed() -> None:
    assert dq.unindexed_search("ab") and dq.unindexed_search("a  zq  _%")
    assert not dq.unindexed_search(None) and not dq.unindexed_search("   ")
    assert not dq.unindexed_search("ab cde") and not dq.unindexed_search("abc")
