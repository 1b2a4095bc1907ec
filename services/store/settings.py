"""The one settings object of the service, read from ``LEGOPT_*`` environment variables.

Every field has an embedded default so that ``legopt`` runs on a machine with nothing installed:
a SQLite file, an artifact directory and a filesystem broker, all under ``./legopt-data``
(relative to the working directory). Compose overrides them with PostgreSQL and Redis URLs.

``get_settings()`` reads the environment once and caches the result; tests build their own with
``Settings.from_env(env={}, database_url=...)`` or ``get_settings().with_overrides(...)``.
"""

from __future__ import annotations

import importlib.util
import os
import re
from collections.abc import Mapping
from functools import lru_cache
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, model_validator

ENV_PREFIX = "LEGOPT_"
DEFAULT_DATA_DIR = Path("legopt-data")


_BUCKET = re.compile(r"^[a-z0-9][a-z0-9.-]{1,61}[a-z0-9]$")
_PREFIX_PART = re.compile(r"^[A-Za-z0-9._-]+$")


def split_s3_url(url: str) -> tuple[str, str]:
    """``"s3://bucket/some/prefix"`` -> ``("bucket", "some/prefix")`` (prefix without slashes at
    either end, possibly empty); ValueError for anything else."""
    if not url.startswith("s3://"):
        raise ValueError(f"artifacts_url {url!r}: expected s3://bucket/prefix (or empty)")
    bucket, _, prefix = url[len("s3://") :].partition("/")
    if not _BUCKET.match(bucket):
        raise ValueError(f"artifacts_url {url!r}: {bucket!r} is not an S3 bucket name")
    prefix = prefix.strip("/")
    parts = prefix.split("/") if prefix else []
    if any(p in (".", "..") or not _PREFIX_PART.match(p) for p in parts):
        raise ValueError(
            f"artifacts_url {url!r}: the key prefix may hold letters, digits, '.', '_', '-' "
            "and '/' between names"
        )
    return bucket, prefix


class Settings(BaseModel):
    """Immutable service configuration (one instance per process, see ``get_settings``).

    Environment variable of each field: ``LEGOPT_`` + the field name in upper case, e.g.
    ``LEGOPT_DATABASE_URL``. Defaults that are ``None`` below are derived from ``data_dir``.
    """

    model_config = ConfigDict(frozen=True, extra="forbid")

    data_dir: Path = Field(
        default=DEFAULT_DATA_DIR,
        description="Root of everything the embedded mode writes (database, artifacts, broker).",
    )
    database_url: str = Field(
        default="",
        description="SQLAlchemy URL; default sqlite:///<data_dir>/legopt.db.",
    )
    broker_url: str = Field(
        default="filesystem://",
        description="Celery broker URL; 'filesystem://' is the embedded broker under broker_dir.",
    )
    result_backend: str | None = Field(
        default=None,
        description="Celery result backend URL; None: none (job state lives in the jobs table).",
    )
    artifact_dir: Path = Field(
        default=Path(),
        description="Directory of the local artifact store; default <data_dir>/artifacts.",
    )
    artifacts_url: str = Field(
        default="",
        description="Where artifacts are stored: '' the local directory artifact_dir; "
        "'s3://bucket/prefix' an S3-compatible object store (endpoint: s3_endpoint_url; "
        "credentials and region: boto3's usual chain, e.g. AWS_ACCESS_KEY_ID, "
        "AWS_SECRET_ACCESS_KEY, AWS_DEFAULT_REGION).",
    )
    s3_endpoint_url: str = Field(
        default="",
        description="Endpoint of the S3-compatible store (MinIO, moto, ...); '': "
        "AWS_ENDPOINT_URL_S3 or AWS_ENDPOINT_URL when set, else AWS's own.",
    )
    artifacts_presign: bool = Field(
        default=False,
        description="Recording downloads from an S3 store answer 307 to a presigned URL of "
        "the object instead of streaming it through the API (the store's endpoint must then "
        "be reachable by the clients).",
    )
    artifacts_presign_seconds: int = Field(
        default=300, gt=0, le=7 * 86_400, description="Lifetime of a presigned URL, seconds."
    )
    mesh_roots: str = Field(
        default="",
        description="Extra folders URDF package:// meshes may be read from (separated by "
        "os.pathsep), beside the installed robot-description packages "
        "(legcore.mesh_packages); a path a user wrote is never opened.",
    )

    # Limits that stop a single request from taking the cluster.
    max_population: int = Field(default=2_000, gt=0, description="Max population per job.")
    max_generations: int = Field(default=5_000, gt=0, description="Max generations per job.")
    max_samples: int = Field(default=20_000, gt=0, description="Max trajectory samples per eval.")
    max_work: int = Field(
        default=500_000_000,
        gt=0,
        description="Max population x generations x samples of one job.",
    )

    worker_memory_limit_mb: int = Field(
        default=2_048,
        gt=0,
        description="Max predicted peak memory of one job in a worker process, MiB "
        "(legcore.memory.predicted_peak_bytes; evaluations are chunked to fit).",
    )

    worker_warmup: bool = Field(
        default=True,
        description="A worker process loads every compiled kernel (legcore.warmup: one tiny "
        "job per study kind) before it takes its first job, so that job runs warm.",
    )
    api_warmup: bool = Field(
        default=True,
        description="An API server validates one minimal job of every study kind in its "
        "validation processes right after it starts (services.api.warmup), so that no "
        "submission waits for a cold validation process; /ready answers 503 until then.",
    )

    # Leases of running jobs.
    lease_seconds: float = Field(default=60.0, gt=0, description="Lease length of a claim.")
    heartbeat_seconds: float = Field(default=15.0, gt=0, description="Heartbeat period.")
    max_attempts: int = Field(
        default=3, gt=0, description="Claims of one job before the reaper fails it."
    )
    checkpoint_every: int = Field(
        default=5, gt=0, description="Generations between two checkpoints of a running job."
    )
    dispatch_period_s: float = Field(
        default=1.0,
        gt=0,
        description="Seconds between two passes of the elected dispatcher (requeue expired "
        "leases, send due queue messages, re-send lost ones).",
    )
    worker_max_memory_mb: int = Field(
        default=0,
        ge=0,
        description="A worker process whose resident memory exceeds this after a job is "
        "replaced by a fresh one (0: never).",
    )

    # Per-API-key quotas (defaults; a key may carry its own, see ``api_keys``).
    quota_active_jobs: int = Field(
        default=20_000,
        gt=0,
        description="Max queued + running jobs of one API key (room for two sweeps of "
        "max_sweep_jobs).",
    )
    max_sweep_jobs: int = Field(
        default=10_000,
        ge=1,
        le=1_000_000,
        description="Most jobs one sweep may expand to; a larger sweep is refused with a 422 "
        "naming its size. A 10^4-job sweep is one request answered in seconds "
        "(benchmarks/bench_sweep_scale.py).",
    )
    quota_cpu_seconds_per_hour: float = Field(
        default=36_000.0,
        gt=0,
        description="Max worker CPU seconds used by one API key's jobs per UTC clock hour.",
    )
    quota_storage_bytes: int = Field(
        default=10 * 1024**3,
        gt=0,
        description="Max bytes stored for one API key (artifacts and specs).",
    )
    rate_limit_per_s: float = Field(
        default=50.0, gt=0, description="Sustained requests per second per API key."
    )
    rate_limit_burst: int = Field(
        default=500, gt=0, description="Requests one API key may make at once before limiting."
    )
    event_stream_s: float = Field(
        default=600.0,
        gt=0,
        description="Seconds a job's event stream (GET /jobs/{id}/events) stays open at most; "
        "the page then opens a new one.",
    )
    validation_processes: int = Field(
        default=1,
        ge=0,
        description="Processes of each API process that validate submissions (robot builds and "
        "job preparation of POST /jobs, /sweeps, /robots: services.api.validation_pool); 0: "
        "in the API process itself (no isolation: for debugging, and tests that patch the "
        "validation code).",
    )
    validation_timeout_s: float = Field(
        default=120.0,
        gt=0,
        description="Longest one submission's validation may run in a validation process; "
        "then that process is killed and the request gets a 422 saying the model could not "
        "be validated.",
    )
    sqlite_busy_timeout_ms: int = Field(
        default=30_000, ge=0, description="SQLite busy_timeout of every connection."
    )
    db_echo: bool = Field(default=False, description="Log every SQL statement.")

    @model_validator(mode="before")
    @classmethod
    def _derive_defaults(cls, data: Any) -> Any:
        """Fill the data-dir-relative defaults (database URL, artifact dir)."""
        if not isinstance(data, dict):
            return data
        data = dict(data)
        data_dir = Path(data.get("data_dir") or DEFAULT_DATA_DIR)
        data["data_dir"] = data_dir
        if not data.get("database_url"):
            data["database_url"] = f"sqlite:///{data_dir.as_posix()}/legopt.db"
        if not data.get("artifact_dir"):
            data["artifact_dir"] = data_dir / "artifacts"
        if data.get("result_backend") == "":
            data["result_backend"] = None
        return data

    @model_validator(mode="after")
    def _check_lease(self) -> Settings:
        if self.heartbeat_seconds >= self.lease_seconds:
            raise ValueError(
                f"heartbeat_seconds ({self.heartbeat_seconds}) must be shorter than "
                f"lease_seconds ({self.lease_seconds})"
            )
        return self

    @model_validator(mode="after")
    def _check_artifacts_url(self) -> Settings:
        if self.artifacts_url:
            split_s3_url(self.artifacts_url)  # ValueError naming what is wrong
        return self

    @property
    def artifacts_s3(self) -> tuple[str, str] | None:
        """``(bucket, key prefix)`` of the S3 artifact store, None for the local directory."""
        return split_s3_url(self.artifacts_url) if self.artifacts_url else None

    @property
    def broker_dir(self) -> Path:
        """Folder of the embedded filesystem broker (used when ``broker_url`` is filesystem://)."""
        return self.data_dir / "broker"

    @property
    def cache_dir(self) -> Path:
        """Folder of persistent caches: compiled numba kernels (``numba/``, unless
        ``NUMBA_CACHE_DIR`` is set) and seed 000 baselines (``baselines/``, unless
        ``LEGOPT_CACHE_DIR`` is set) — see :meth:`cache_environment`."""
        return self.data_dir / "cache"

    def cache_environment(self) -> dict[str, str]:
        """Environment variables that make a worker start warm (issue 12): ``LEGOPT_CACHE_DIR``
        (``legcore.result_cache``) and, when the installed legcore package is not writable
        (numba's default cache is its ``__pycache__``), ``NUMBA_CACHE_DIR`` (numba reads it
        once, on import: set it before legcore is imported). Values already in the environment
        (e.g. the image's ahead-of-time kernel cache) win: ``services.embedded.worker_env``
        and ``services.worker.celery_app`` use ``setdefault``."""
        env = {"LEGOPT_CACHE_DIR": str(self.cache_dir.absolute())}
        spec = importlib.util.find_spec("legcore")
        package = Path(spec.origin).parent if spec is not None and spec.origin else None
        if package is None or not os.access(package, os.W_OK):  # numba's default: in-tree
            env["NUMBA_CACHE_DIR"] = str((self.cache_dir / "numba").absolute())
        return env

    @property
    def mesh_root_dirs(self) -> tuple[Path, ...]:
        """Every folder a recording may read URDF meshes from: the installed packages' and
        ``mesh_roots`` (``legcore.mesh_packages.mesh_roots``)."""
        from legcore.mesh_packages import mesh_roots

        return mesh_roots([p for p in self.mesh_roots.split(os.pathsep) if p])

    @property
    def is_sqlite(self) -> bool:
        """True when the database is SQLite (embedded mode)."""
        return self.database_url.startswith("sqlite")

    def check_job_size(
        self, population: int, generations: int, samples: int = 1, peak_bytes: int = 0
    ) -> str | None:
        """Return why a job of this size is refused, or None when it fits the limits.

        ``peak_bytes``: the job's predicted peak memory (``JobSize.peak_bytes``), checked
        against ``worker_memory_limit_mb``.
        """
        if population > self.max_population:
            return f"population {population} exceeds the limit {self.max_population}"
        if generations > self.max_generations:
            return f"generations {generations} exceed the limit {self.max_generations}"
        if samples > self.max_samples:
            return f"samples {samples} exceed the limit {self.max_samples}"
        work = population * generations * samples
        if work > self.max_work:
            return f"population x generations x samples = {work} exceeds the limit {self.max_work}"
        if peak_bytes > self.worker_memory_limit_mb * 1024**2:
            return (
                f"memory: predicted peak {peak_bytes / 1024**2:.0f} MiB exceeds the per-worker "
                f"limit {self.worker_memory_limit_mb} MiB (worker_memory_limit_mb)"
            )
        return None

    def with_overrides(self, **overrides: Any) -> Settings:
        """A validated copy with some fields replaced.

        Fields derived from ``data_dir`` keep their current value unless overridden too.
        """
        data = self.model_dump()
        data.update(overrides)
        return Settings(**data)

    @classmethod
    def from_env(cls, env: Mapping[str, str] | None = None, **overrides: Any) -> Settings:
        """Build settings from ``LEGOPT_*`` variables of ``env`` (default ``os.environ``).

        Keyword ``overrides`` win over the environment; ``env={}`` ignores the environment.
        Unknown ``LEGOPT_*`` variables are ignored (other components own some of them).
        """
        source = os.environ if env is None else env
        data: dict[str, Any] = {}
        for name in cls.model_fields:
            value = source.get(ENV_PREFIX + name.upper())
            if value is not None:
                data[name] = value
        data.update(overrides)
        return cls(**data)


@lru_cache(maxsize=1)
def get_settings() -> Settings:
    """The process-wide settings, read from the environment on first call and cached.

    Call ``get_settings.cache_clear()`` after changing the environment (tests).
    """
    return Settings.from_env()
