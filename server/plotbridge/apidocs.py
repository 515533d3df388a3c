"""The API pages at /docs (Swagger UI) and /redoc, working offline.

Their scripts and styles come from the pinned `fastapi-offline` package (MIT,
Swagger UI and ReDoc bundled) and are served from /docs/assets; nothing is
loaded from a CDN. The pages carry a Content-Security-Policy that lets the
browser load only from this server, so the links and images the bundles name
(ReDoc's sidebar logo, Swagger UI's validator badge) are never fetched.
"""

from __future__ import annotations

from pathlib import Path

import fastapi_offline
from fastapi import FastAPI
from fastapi.openapi.docs import (
    get_redoc_html,
    get_swagger_ui_html,
    get_swagger_ui_oauth2_redirect_html,
)
from fastapi.responses import HTMLResponse
from fastapi.staticfiles import StaticFiles

from plotbridge.access import PUBLIC_PATHS

ASSETS_DIR = Path(fastapi_offline.__file__).resolve().parent / "static"
ASSETS_URL = "/docs/assets"
CSP = (
    "default-src 'self'; script-src 'self' 'unsafe-inline'; style-src 'self' 'unsafe-inline'; "
    "img-src 'self' data:; font-src 'self' data:; worker-src 'self' blob:; "
    "connect-src 'self'; frame-ancestors 'none'"
)
SWAGGER_PARAMETERS = {"validatorUrl": None}  # the default badge asks validator.swagger.io


# What /docs groups the endpoints by: the first path prefix that matches names the tag.
TAGS: tuple[tuple[str, str, str], ...] = (
    ("/api/jobs", "jobs", "Upload, list and act on jobs (each job lists its `actions`)"),
    ("/api/patterns", "jobs", ""),
    ("/api/pens", "pens", "The pen library: servo positions, speed, odometers"),
    ("/api/plotters", "plotters", "Each plotter's board: state, stop, home, jog, settings"),
    ("/api/machine", "plotters", ""),
    ("/api/estop", "plotters", ""),
    ("/api/sim", "virtual plotter", "What the virtual plotter's pen drew"),
    ("/api/settings", "settings", "Server settings: webhooks"),
    ("/", "session", "Log in and out, health, server facts"),
)
SECURITY_SCHEMES = {
    "token": {"type": "http", "scheme": "bearer",
              "description": "`Authorization: Bearer TOKEN`: the data directory's token, or "
                             "an API key (`plotbridge keys add NAME --role ROLE`)"},
    "session": {"type": "apiKey", "in": "cookie", "name": "plotbridge_session",
                "description": "the browser's session after `POST /api/login`; a request that "
                               "changes something also sends the header `X-Plotbridge: 1`"},
}  # fmt: skip


def _tag(path: str) -> str:
    return next(tag for prefix, tag, _ in TAGS if path.startswith(prefix))


def describe_api(app: FastAPI) -> None:
    """The OpenAPI document declares how to authenticate (a bearer token or the session
    cookie; the public paths need neither) and groups every endpoint by tag."""
    build = app.openapi

    def openapi() -> dict:
        if app.openapi_schema is None:
            schema = build()
            for path, operations in schema.get("paths", {}).items():
                for operation in operations.values():
                    if not operation.get("tags"):
                        operation["tags"] = [_tag(path)]
            schema.setdefault("components", {})["securitySchemes"] = SECURITY_SCHEMES
            schema["security"] = [{"token": []}, {"session": []}]
            for path in PUBLIC_PATHS:
                for operation in schema.get("paths", {}).get(path, {}).values():
                    operation["security"] = []
            schema["tags"] = [{"name": tag, "description": text} for _, tag, text in TAGS if text]
        return app.openapi_schema

    app.openapi = openapi  # type: ignore[method-assign]


def _page(response: HTMLResponse) -> HTMLResponse:
    response.headers["Content-Security-Policy"] = CSP
    return response


def mount_docs(app: FastAPI, docs_url: str = "/docs", redoc_url: str = "/redoc") -> None:
    """Add both pages and their assets; create the app with docs_url=None, redoc_url=None."""
    describe_api(app)
    openapi_url = app.openapi_url or "/openapi.json"
    oauth2_url = f"{docs_url}/oauth2-redirect"
    favicon = f"{ASSETS_URL}/favicon.png"
    app.mount(ASSETS_URL, StaticFiles(directory=ASSETS_DIR), name="docs-assets")

    @app.get(docs_url, include_in_schema=False)
    async def swagger() -> HTMLResponse:
        return _page(get_swagger_ui_html(
            openapi_url=openapi_url, title=f"{app.title} API",
            swagger_js_url=f"{ASSETS_URL}/swagger-ui-bundle.js",
            swagger_css_url=f"{ASSETS_URL}/swagger-ui.css", swagger_favicon_url=favicon,
            oauth2_redirect_url=oauth2_url, swagger_ui_parameters=SWAGGER_PARAMETERS,
        ))  # fmt: skip

    @app.get(oauth2_url, include_in_schema=False)
    async def swagger_redirect() -> HTMLResponse:
        return _page(get_swagger_ui_oauth2_redirect_html())

    @app.get(redoc_url, include_in_schema=False)
    async def redoc() -> HTMLResponse:
        return _page(get_redoc_html(
            openapi_url=openapi_url, title=f"{app.title} API",
            redoc_js_url=f"{ASSETS_URL}/redoc.standalone.js", redoc_favicon_url=favicon,
            with_google_fonts=False,
        ))  # fmt: skip
