"""API keys: your own key's limits and usage; admins create, list and revoke keys."""

from __future__ import annotations

from datetime import datetime, timedelta
from typing import Annotated

from fastapi import APIRouter, Body, HTTPException, status
from pydantic import BaseModel, ConfigDict, Field, StrictInt

from services.api.deps import AdminKey, Context, CurrentKey, Pagination
from services.api.errors import not_found
from services.api.schemas import ErrorOut, Page
from services.store import api_keys
from services.store.keys import generate_api_key
from services.store.quotas import usage
from services.store.records import ApiKeyRecord
from services.store.sql import now_utc
from services.store.states import KeyRole

router = APIRouter(tags=["keys"])

_403: dict[int | str, dict[str, object]] = {
    403: {"model": ErrorOut, "description": "Needs an admin API key."}
}


class KeyOut(BaseModel):
    """An API key (never its secret): role, validity and its own quota limits (null: the
    service defaults)."""

    id: str
    name: str
    role: KeyRole
    created_at: datetime
    expires_at: datetime | None = None
    revoked_at: datetime | None = None
    max_active_jobs: int | None = None
    max_cpu_seconds_per_hour: float | None = None
    max_storage_bytes: int | None = None

    @classmethod
    def from_record(cls, k: ApiKeyRecord) -> KeyOut:
        return cls(
            id=k.id,
            name=k.name,
            role=k.role,
            created_at=k.created_at,
            expires_at=k.expires_at,
            revoked_at=k.revoked_at,
            max_active_jobs=k.max_active_jobs,
            max_cpu_seconds_per_hour=k.max_cpu_seconds_per_hour,
            max_storage_bytes=k.max_storage_bytes,
        )


class KeyCreate(BaseModel):
    """A new key: a label, a role, an optional lifetime and quota limits."""

    model_config = ConfigDict(extra="forbid")

    name: str = Field(min_length=1, max_length=200, description="A label (who uses it).")
    role: KeyRole = Field(default=KeyRole.USER, description="user, or admin (manages keys).")
    expires_in_days: float | None = Field(
        default=None, gt=0, le=3650, description="Days until the key stops working (none: never)."
    )
    max_active_jobs: StrictInt | None = Field(default=None, gt=0, le=1_000_000)
    max_cpu_seconds_per_hour: float | None = Field(default=None, gt=0, le=1e9)
    max_storage_bytes: StrictInt | None = Field(default=None, gt=0, le=2**62)


class KeyCreated(KeyOut):
    """The created key with its secret, shown this once only."""

    key: str = Field(description="The secret to send as X-API-Key; it is not stored.")


class UsageOut(BaseModel):
    """What your key uses now, and its limits."""

    key: KeyOut
    active_jobs: int
    max_active_jobs: int
    cpu_seconds_this_hour: float = Field(description="Worker CPU s in the current UTC hour.")
    max_cpu_seconds_per_hour: float
    stored_bytes: int = Field(description="Artifacts plus stored specs, bytes.")
    max_storage_bytes: int


@router.get("/keys/me", response_model=UsageOut, summary="Your key: usage and quotas")
def my_key(key: CurrentKey, ctx: Context) -> UsageOut:
    """Jobs queued or running, CPU seconds this hour and stored bytes, beside the limits."""
    with ctx.read() as session:
        used = usage(session, key.id)
    s = ctx.settings
    return UsageOut(
        key=KeyOut.from_record(key),
        active_jobs=used.active_jobs,
        max_active_jobs=key.max_active_jobs or s.quota_active_jobs,
        cpu_seconds_this_hour=used.cpu_seconds_this_hour,
        max_cpu_seconds_per_hour=key.max_cpu_seconds_per_hour or s.quota_cpu_seconds_per_hour,
        stored_bytes=used.stored_bytes,
        max_storage_bytes=key.max_storage_bytes or s.quota_storage_bytes,
    )


@router.get(
    "/keys", response_model=Page[KeyOut], summary="List API keys (admin)", responses=_403
)
def list_keys(_admin: AdminKey, ctx: Context, page: Pagination) -> Page[KeyOut]:
    """Every key, oldest first."""
    with ctx.read() as session:
        keys = api_keys.list_api_keys(session, limit=page.limit, offset=page.offset)
    return Page[KeyOut](
        items=[KeyOut.from_record(k) for k in keys.items],
        total=keys.total,
        limit=keys.limit,
        offset=keys.offset,
    )


@router.post(
    "/keys",
    status_code=status.HTTP_201_CREATED,
    response_model=KeyCreated,
    summary="Create an API key (admin)",
    responses=_403,
)
def create_key(
    body: Annotated[KeyCreate, Body()], _admin: AdminKey, ctx: Context
) -> KeyCreated:
    """The secret is in the answer only; store it, it cannot be shown again."""
    raw, key_hash = generate_api_key()
    expires = None
    if body.expires_in_days is not None:
        expires = now_utc() + timedelta(days=body.expires_in_days)
    with ctx.write() as session:
        record = api_keys.create_api_key(
            session,
            name=body.name,
            key_hash=key_hash,
            role=body.role,
            expires_at=expires,
            max_active_jobs=body.max_active_jobs,
            max_cpu_seconds_per_hour=body.max_cpu_seconds_per_hour,
            max_storage_bytes=body.max_storage_bytes,
        )
    return KeyCreated(**KeyOut.from_record(record).model_dump(), key=raw)


@router.post(
    "/keys/{key_id}/revoke",
    response_model=KeyOut,
    summary="Revoke an API key (admin)",
    responses={
        **_403,
        404: {"model": ErrorOut, "description": "No such key."},
        409: {"model": ErrorOut, "description": "The admin key of the request itself."},
    },
)
def revoke_key(key_id: str, admin: AdminKey, ctx: Context) -> KeyOut:
    """The key is refused from now on (401); its jobs, sweeps and robots stay."""
    if key_id == admin.id:
        raise HTTPException(
            status.HTTP_409_CONFLICT, "an admin cannot revoke the key it is using"
        )
    with ctx.write() as session:
        if api_keys.get_api_key(session, key_id) is None:
            raise not_found("API key", key_id)
        api_keys.revoke_api_key(session, key_id)
        record = api_keys.get_api_key(session, key_id)
    assert record is not None
    return KeyOut.from_record(record)
