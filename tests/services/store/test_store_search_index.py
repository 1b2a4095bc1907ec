"""The jobs page's word search reads an index (issue 23, item 3): an FTS5 trigram table on
SQLite, a pg_trgm GIN index on PostgreSQL (revision 0009; ``create_all`` makes them too).

Search by the index finds exactly what the LIKE scan it replaces finds — every word, short
words (which no trigram answers: still LIKE), LIKE's own wildcard characters, quotes, case, other
filters, every order, keyset and offset pages, a word in more matches than are counted. The
index itself (its table follows the labels, the plans read it, stores without it):
``test_store_search_plumbing``."""

from __future__ import annotations

from typing import Any

import pytest
from search_jobs import N, _fill, _ids, _texts
from sqlalchemy import Engine
from sqlalchemy.orm import Session, sessionmaker

from services.store import api_keys
from services.store import dashboard_queries as dq
from services.store.states import JobStatus

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


def test_search_finds_what_the_like_scan_finds(filled: tuple[sessionmaker[Session], str]) -> None:
    factory, key_id = filled
    with factory() as s:
        texts = _texts(s, key_id)
        assert len(texts) == N
        for q in QUERIES:
            words = q.lower().split()
            want = {j for j, t in texts.items() if all(w in t for w in words)}
            f = dq.JobFilter(search=q)
            page = dq.list_job_rows(s, key_id, f, limit=100)
            scan = dq.list_job_rows(s, key_id, f, limit=100, search_index=False)
            assert set(_ids(page)) == want, q
            assert _ids(page) == _ids(scan) and page.total == scan.total == len(want), q
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
