"""SQL store of LegOpt: settings, tables, sessions, repository, job lifecycle, artifacts.

Typical use::

    from services.store import session_scope, create_job, claim_job

    with session_scope() as s:
        job = create_job(s, owner_key_id=key.id, spec=spec, total_generations=100)
    # ... send job.id to the queue after the commit ...

Modules: ``settings`` (``Settings``, ``get_settings``), ``tables`` (the schema), ``session``
(engines, ``session_scope``), ``records`` (frozen records handed out), ``repository``
(create/get/list), ``lifecycle`` (claims, leases, cancellation, outcome, reaper), ``progress``
(generations and checkpoints), ``artifacts`` (the artifact store: a local directory or S3),
``keys`` (API key hashing), ``migrate`` (Alembic from Python).
"""

from services.store.api_keys import (
    create_api_key,
    delete_api_key,
    get_api_key,
    get_api_key_by_hash,
    list_api_keys,
)
from services.store.artifacts import ArtifactStore, StoredFile
from services.store.errors import (
    ArtifactError,
    ArtifactMissingError,
    ArtifactUnavailableError,
    ChecksumMismatchError,
    ConflictError,
    LeaseLostError,
    NotFoundError,
    StoreError,
    UnsafePathError,
)
from services.store.keys import generate_api_key, hash_api_key
from services.store.lifecycle import (
    claim_job,
    expired_leases,
    fail_job,
    finish_job,
    heartbeat,
    is_cancel_requested,
    mark_cancelled,
    request_cancel,
    request_cancels,
    requeue_expired,
)
from services.store.output_queries import (
    get_artifact,
    get_result,
    list_artifacts,
    list_baselines,
    list_generations,
    list_pareto,
)
from services.store.progress import latest_checkpoint, record_generation, save_checkpoint
from services.store.records import (
    ApiKeyRecord,
    ArtifactIn,
    ArtifactRecord,
    BaselineIn,
    BaselineRecord,
    CheckpointRecord,
    GenerationRecord,
    JobRecord,
    Page,
    ParetoPointIn,
    ParetoPointRecord,
    ReapReport,
    ResultIn,
    ResultRecord,
    RobotRecord,
    SweepRecord,
)
from services.store.repository import (
    count_jobs_by_status,
    create_job,
    create_robot,
    create_sweep,
    delete_robot,
    get_job,
    get_robot,
    get_robot_by_name,
    get_sweep,
    list_jobs,
    list_robots,
    list_sweeps,
)
from services.store.session import (
    engine_from_settings,
    get_engine,
    get_session_factory,
    make_engine,
    make_session_factory,
    reset_engine,
    session_scope,
)
from services.store.settings import Settings, get_settings
from services.store.states import JobStatus, RobotSource
from services.store.tables import Base

__all__ = [
    "ApiKeyRecord",
    "ArtifactError",
    "ArtifactIn",
    "ArtifactMissingError",
    "ArtifactRecord",
    "ArtifactStore",
    "ArtifactUnavailableError",
    "Base",
    "BaselineIn",
    "BaselineRecord",
    "CheckpointRecord",
    "ChecksumMismatchError",
    "ConflictError",
    "GenerationRecord",
    "JobRecord",
    "JobStatus",
    "LeaseLostError",
    "NotFoundError",
    "Page",
    "ParetoPointIn",
    "ParetoPointRecord",
    "ReapReport",
    "ResultIn",
    "ResultRecord",
    "RobotRecord",
    "RobotSource",
    "Settings",
    "StoreError",
    "StoredFile",
    "SweepRecord",
    "UnsafePathError",
    "claim_job",
    "count_jobs_by_status",
    "create_api_key",
    "create_job",
    "create_robot",
    "create_sweep",
    "delete_api_key",
    "delete_robot",
    "engine_from_settings",
    "expired_leases",
    "fail_job",
    "finish_job",
    "generate_api_key",
    "get_api_key",
    "get_api_key_by_hash",
    "get_artifact",
    "get_engine",
    "get_job",
    "get_result",
    "get_robot",
    "get_robot_by_name",
    "get_session_factory",
    "get_settings",
    "get_sweep",
    "hash_api_key",
    "heartbeat",
    "is_cancel_requested",
    "latest_checkpoint",
    "list_api_keys",
    "list_artifacts",
    "list_baselines",
    "list_generations",
    "list_jobs",
    "list_pareto",
    "list_robots",
    "list_sweeps",
    "make_engine",
    "make_session_factory",
    "mark_cancelled",
    "record_generation",
    "request_cancel",
    "request_cancels",
    "requeue_expired",
    "reset_engine",
    "save_checkpoint",
    "session_scope",
]
