"""The web dashboard, served by the API itself: a small ES-module front end (``static/``), the
OpenAPI page with Swagger UI's files served locally, and the Rerun web viewer of the installed
rerun-sdk (``viewer_assets``). Nothing is loaded from the internet.

    /                 the dashboard (jobs, sweeps, robots; log in with an API key)
    /docs, /api/v1    → /api/v1/docs, the OpenAPI page
    /static/…         the dashboard's files and the vendored libraries (plotly.js, Swagger UI)
    /viewer/          the Rerun web viewer page the dashboard embeds

Every page is a static file: the data comes from the API with the key the user typed, kept in
the browser's session storage, so these routes need no key and hold nothing of anyone's.
"""

from __future__ import annotations

from pathlib import Path

from fastapi import FastAPI
from fastapi.openapi.docs import get_swagger_ui_html
from fastapi.responses import FileResponse, HTMLResponse, RedirectResponse, Response
from fastapi.staticfiles import StaticFiles
from starlette.applications import Starlette
from starlette.requests import Request
from starlette.routing import Route

from services.store.settings import Settings

__all__ = ["STATIC_DIR", "mount_dashboard", "viewer_app"]

STATIC_DIR = Path(__file__).resolve().parent / "static"
_NO_CACHE = {"Cache-Control": "no-cache"}
#: The pages may load and call nothing but this server (the Rerun viewer would otherwise send
#: usage analytics to its makers): the browser refuses any other origin.
_SELF_ONLY = (
    "default-src 'self'; connect-src 'self'; img-src 'self' data: blob:; "
    "worker-src 'self' blob:; frame-src 'self'; frame-ancestors 'self'; base-uri 'none'; "
    "form-action 'self'; "
)
#: An empty inline ``<style>`` element (the SHA-256 of the empty string) and nothing else
#: inline: plotly.js creates one empty ``<style>`` per page and per plot and adds its rules
#: through the CSSOM (``insertRule``, which a policy does not restrict); the dashboard's own
#: styles are in ``style.css`` and its scripts set element styles through the CSSOM too, never
#: as ``style=""`` attributes. Neither plotly.js (the gl3d bundle: its 2-D and 3-D scatter
#: traces) nor the dashboard's modules evaluate strings, so no ``'unsafe-eval'``.
_EMPTY_STYLE = "'sha256-47DEQpj8HBSa+/TImW+5JCeuQeRkm5NMpJWZG3hSuFU='"
DASHBOARD_HEADERS = {
    **_NO_CACHE,
    "Content-Security-Policy": _SELF_ONLY + f"style-src 'self' {_EMPTY_STYLE}; script-src 'self'",
}
#: The Rerun viewer's page: its scripts are files; ``'wasm-unsafe-eval'`` lets it compile its
#: WebAssembly (the viewer itself), nothing more.
_VIEWER_SCRIPTS = "style-src 'self'; script-src 'self' 'wasm-unsafe-eval'"
VIEWER_HEADERS = {**_NO_CACHE, "Content-Security-Policy": _SELF_ONLY + _VIEWER_SCRIPTS}
#: Swagger UI: FastAPI's page starts the bundle from an inline script, and the bundle styles
#: its elements with ``style=""`` attributes.
DOCS_HEADERS = {
    "Content-Security-Policy": _SELF_ONLY
    + "style-src 'self' 'unsafe-inline'; script-src 'self' 'unsafe-inline'"
}


def viewer_app(settings: Settings) -> Starlette:
    """``/viewer``: the dashboard's viewer page and the installed rerun-sdk's viewer files
    (extracted on first request, see ``services.web.viewer_assets``)."""
    from services.web.viewer_assets import ViewerAssetsError, ensure_viewer_assets

    async def page(_request: Request) -> Response:
        return FileResponse(STATIC_DIR / "viewer.html", headers=VIEWER_HEADERS)

    def asset(name: str, media_type: str) -> Route:
        async def serve(_request: Request) -> Response:
            from fastapi.concurrency import run_in_threadpool

            try:
                directory = await run_in_threadpool(ensure_viewer_assets, settings.data_dir)
            except ViewerAssetsError as exc:
                return Response(f"the Rerun web viewer is unavailable: {exc}", status_code=503)
            return FileResponse(
                directory / name,
                media_type=media_type,
                headers={"Cache-Control": "max-age=86400"},
            )

        return Route(f"/{name}", serve)

    return Starlette(
        routes=[
            Route("/", page),
            asset("re_viewer.js", "text/javascript"),
            asset("re_viewer_bg.wasm", "application/wasm"),
        ]
    )


def mount_dashboard(app: FastAPI, settings: Settings, api_prefix: str) -> None:
    """Add the dashboard's routes to ``app``: ``/``, ``/docs``, ``{api_prefix}`` and
    ``{api_prefix}/docs`` (Swagger UI from local files), ``/static`` and ``/viewer``."""
    docs = f"{api_prefix}/docs"

    @app.get("/", include_in_schema=False)
    def dashboard() -> FileResponse:
        return FileResponse(STATIC_DIR / "index.html", headers=DASHBOARD_HEADERS)

    @app.get("/docs", include_in_schema=False)
    def docs_redirect() -> RedirectResponse:
        return RedirectResponse(docs)

    @app.get(api_prefix, include_in_schema=False)
    def api_root() -> RedirectResponse:
        return RedirectResponse(docs)

    @app.get(docs, include_in_schema=False)
    def swagger_ui() -> HTMLResponse:
        page = get_swagger_ui_html(
            openapi_url=app.openapi_url or f"{api_prefix}/openapi.json",
            title=f"{app.title} API",
            swagger_js_url="/static/vendor/swagger-ui/swagger-ui-bundle.js",
            swagger_css_url="/static/vendor/swagger-ui/swagger-ui.css",
            swagger_favicon_url="/static/favicon.svg",
            swagger_ui_parameters={"validatorUrl": None},  # no online validator badge
        )
        page.headers.update(DOCS_HEADERS)  # like the dashboard: nothing but this server
        return page

    app.mount("/static", StaticFiles(directory=STATIC_DIR), name="static")
    app.mount("/viewer", viewer_app(settings), name="viewer")
