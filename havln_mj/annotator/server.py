"""The annotation page's HTTP server (standard library ``http.server``), on localhost only.

One request at a time, in the serving thread: rendering shares the process's one GL context,
which is used from one thread. Routes:

===========================  ===============================================================
``GET /``                    the page (``static/index.html``, ``app.js``, ``style.css``)
``GET /api/scene``           the map (:func:`~havln_mj.annotator.plan.scene_plan`), the
                             activity catalog, the people and the placement file's path
``PUT /api/people``          replace the people (JSON list); answers the people as placed
``GET /api/view.png``        the agent's view: ``viewpoint``, ``heading``, ``elevation`` (°),
                             ``t`` (s)
``GET /api/preview.mp4``     a clip of the person on ``viewpoint`` (H.264)
``POST /api/save``           write the placement file (``{"path": ...}`` optional)
``POST /api/load``           read the placement file (``{"path": ...}`` optional)
===========================  ===============================================================

Bad input answers 400 with ``{"error": message}``. Requests must name this server as their
host, and writes must be JSON from this page's own origin, so other web pages cannot use it.
"""

from __future__ import annotations

import http.server
import json
import sys
import traceback
from importlib import resources
from pathlib import Path
from urllib.parse import parse_qs, urlsplit

from havln_mj.annotator.session import AnnotationSession
from havln_mj.errors import HavlnError, InvalidArgumentError

_STATIC = {
    "/": ("index.html", "text/html; charset=utf-8"),
    "/static/app.js": ("app.js", "text/javascript; charset=utf-8"),
    "/static/style.css": ("style.css", "text/css; charset=utf-8"),
}


class _Handler(http.server.BaseHTTPRequestHandler):
    server: AnnotationServer

    # ------------------------------------------------------------------ plumbing

    def log_message(self, format: str, *args: object) -> None:
        if self.server.verbose:
            super().log_message(format, *args)

    def _send(self, status: int, body: bytes, content_type: str) -> None:
        self.send_response(status)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)

    def _json(self, value: object, status: int = 200) -> None:
        self._send(status, json.dumps(value).encode(), "application/json")

    def _host_ok(self) -> bool:
        port = self.server.server_address[1]
        allowed = {f"{h}:{port}" for h in ("127.0.0.1", "localhost", "[::1]")}
        if self.headers.get("Host") not in allowed:
            return False
        origin = self.headers.get("Origin")
        return origin is None or origin in {f"http://{h}" for h in allowed}

    def _body(self) -> object:
        if self.headers.get("Content-Type", "").split(";")[0].strip() != "application/json":
            raise InvalidArgumentError("send JSON (Content-Type: application/json)")
        length = int(self.headers.get("Content-Length") or 0)
        try:
            return json.loads(self.rfile.read(length) or b"null")
        except ValueError as exc:
            raise InvalidArgumentError(f"request body is not JSON ({exc})") from None

    def _dispatch(self, routes: dict) -> None:
        if not self._host_ok():
            self._json({"error": "requests must come from this page on localhost"}, 403)
            return
        url = urlsplit(self.path)
        route = routes.get(url.path)
        if route is None:
            self._json({"error": f"no such page: {url.path}"}, 404)
            return
        query = {k: v[-1] for k, v in parse_qs(url.query).items()}
        try:
            route(query)
        except ConnectionError:
            pass  # the page dropped the request (e.g. a view superseded by the next one)
        except HavlnError as exc:
            self._json({"error": str(exc)}, 400)
        except Exception as exc:  # the page shows it; the server keeps serving
            traceback.print_exc(file=sys.stderr)
            self._json({"error": f"{type(exc).__name__}: {exc}"}, 500)

    def do_GET(self) -> None:
        """Serves the page, the scene, views and previews."""
        routes = {path: self._static for path in _STATIC}
        routes |= {
            "/api/scene": self._scene,
            "/api/view.png": self._view,
            "/api/preview.mp4": self._preview,
        }
        self._dispatch(routes)

    def do_PUT(self) -> None:
        """Replaces the people."""
        self._dispatch({"/api/people": self._people})

    def do_POST(self) -> None:
        """Saves or loads the placement file."""
        self._dispatch({"/api/save": self._save, "/api/load": self._load})

    # ------------------------------------------------------------------ routes

    def _static(self, query: dict) -> None:
        name, content_type = _STATIC[urlsplit(self.path).path]
        body = resources.files("havln_mj.annotator").joinpath("static", name).read_bytes()
        self._send(200, body, content_type)

    def _scene(self, query: dict) -> None:
        s = self.server.session
        self._json(
            {
                "plan": s.plan,
                "catalog": s.catalog_json(),
                "people": s.people_json(),
                "placements": str(s.path),
                "view": {"width": s.settings.width, "height": s.settings.height},
            }
        )

    def _people(self, query: dict) -> None:
        self.server.session.set_people(self._body())
        self._json(self.server.session.people_json())

    @staticmethod
    def _arg(query: dict, name: str, default: str | None = None) -> str:
        if name in query:
            return query[name]
        if default is None:
            raise InvalidArgumentError(f"missing query parameter {name!r}")
        return default

    @staticmethod
    def _float(query: dict, name: str, default: str) -> float:
        value = _Handler._arg(query, name, default)
        try:
            return float(value)
        except ValueError:
            raise InvalidArgumentError(f"{name} must be a number, got {value!r}") from None

    def _view(self, query: dict) -> None:
        png = self.server.session.view_png(
            self._arg(query, "viewpoint"),
            self._float(query, "heading", "0"),
            self._float(query, "elevation", "0"),
            self._float(query, "t", "0"),
        )
        self._send(200, png, "image/png")

    def _preview(self, query: dict) -> None:
        clip = self.server.session.preview_mp4(self._arg(query, "viewpoint"))
        self._send(200, clip, "video/mp4")

    def _file_arg(self) -> Path | None:
        body = self._body()
        path = body.get("path") if isinstance(body, dict) else None
        return Path(path) if path else None

    def _save(self, query: dict) -> None:
        s = self.server.session
        path = s.save(self._file_arg())
        self._json({"path": str(path), "people": len(s.people)})

    def _load(self, query: dict) -> None:
        s = self.server.session
        s.load(self._file_arg())
        self._json({"path": str(s.path), "people": s.people_json()})


class AnnotationServer(http.server.HTTPServer):
    """Serves one :class:`AnnotationSession` on ``host:port`` (port 0 picks a free one).

    Args:
        session: The scan being annotated.
        host: Interface to listen on (default localhost only).
        port: TCP port; 0 lets the system choose.
        verbose: Log every request to stderr.
    """

    def __init__(
        self,
        session: AnnotationSession,
        host: str = "127.0.0.1",
        port: int = 8765,
        verbose: bool = False,
    ) -> None:
        super().__init__((host, port), _Handler)
        self.session = session
        self.verbose = verbose

    @property
    def url(self) -> str:
        """The page's address."""
        host, port = self.server_address[:2]
        return f"http://{host}:{port}/"
