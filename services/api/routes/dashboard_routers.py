"""The routers of the web dashboard's API, in the order the app includes them (behind the
API key, like every other ``/api/v1`` route): the jobs page, one job's views, sweep cells and
downloads."""

from __future__ import annotations

from fastapi import APIRouter

from services.api.routes import dashboard, exports, job_views, live, sweep_views, trials

DASHBOARD_ROUTERS: tuple[APIRouter, ...] = (
    dashboard.router,
    job_views.router,
    trials.router,
    live.router,
    sweep_views.router,
    exports.router,
)

__all__ = ["DASHBOARD_ROUTERS"]
