"""Headers every response of the service carries (API answers, downloads, the dashboard's files,
errors): ``X-Content-Type-Options: nosniff``, so that a browser never reads a download (a CSV
of the tenant's text, a recording) or a JSON answer as HTML or script whatever it holds.

:class:`SecurityHeadersMiddleware` is the app's outermost middleware, so the answers of the
other middlewares (413, the JSON guard's 422) get the headers too; a response that sets one of
them itself keeps its own value. The logged 500 of an unexpected error is sent from outside
every middleware: ``services.api.errors`` adds :data:`SECURITY_HEADERS` to it itself.
"""

from __future__ import annotations

from collections.abc import Mapping

from starlette.datastructures import MutableHeaders
from starlette.types import ASGIApp, Message, Receive, Scope, Send

__all__ = ["SECURITY_HEADERS", "SecurityHeadersMiddleware"]

#: Sent with every HTTP response.
SECURITY_HEADERS: Mapping[str, str] = {"X-Content-Type-Options": "nosniff"}


class SecurityHeadersMiddleware:
    """Add ``headers`` (default :data:`SECURITY_HEADERS`) to every HTTP response that does not
    set them itself (pure ASGI: streamed bodies pass through untouched)."""

    def __init__(self, app: ASGIApp, headers: Mapping[str, str] = SECURITY_HEADERS) -> None:
        self.app = app
        self.headers = dict(headers)

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        """Pass the request on; add the headers to the response's start message."""
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return

        async def send_with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                headers = MutableHeaders(scope=message)
                for name, value in self.headers.items():
                    headers.setdefault(name, value)
            await send(message)

        await self.app(scope, receive, send_with_headers)
