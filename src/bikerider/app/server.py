"""The HTTP server of ``bikerider serve``: the page, its JSON endpoints, uploads and downloads.

:class:`App` holds the page's work as plain methods (each takes the decoded request and returns a
:class:`Reply`), so the tests call them without a server; :class:`Handler` only routes requests to
them.  The server is the standard library's :class:`http.server.ThreadingHTTPServer`, bound to
127.0.0.1 unless told otherwise; it answers only requests whose ``Host`` names the address it is
bound to (or ``localhost``), takes JSON only as ``application/json`` and caps every body's size.
"""

from __future__ import annotations

import json
import logging
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from pathlib import Path
from urllib.parse import parse_qs, unquote, urlsplit

from bikerider.app import bicycle, downloads, dynamics
from bikerider.app.gap_jobs import GapJobs
from bikerider.app.uploads import LIMITS, UploadFolders
from bikerider.errors import BikeriderError, InputError

LOG = logging.getLogger(__name__)
JSON_LIMIT = 1 << 20
"""Largest JSON request body [bytes] (a parameter table is about 2 kB)."""
STATIC = {"index.html": "text/html; charset=utf-8", "app.js": "text/javascript; charset=utf-8", "app.css": "text/css"}
"""The page's files, shipped in ``bikerider/app/static``."""
SECURITY_HEADERS = {
    "X-Content-Type-Options": "nosniff",
    "Content-Security-Policy": "default-src 'self'; img-src 'self' data: blob:; style-src 'self'; object-src 'none'",
    "Referrer-Policy": "no-referrer",
}


@dataclass
class Reply:
    """An answer: status, content type, body, and a file name for downloads."""

    body: bytes
    content_type: str = "application/json"
    status: int = 200
    filename: str | None = None
    headers: dict[str, str] = field(default_factory=dict)

    @classmethod
    def json(cls, value, status: int = 200) -> Reply:
        return cls(json.dumps(value, allow_nan=False).encode(), status=status)

    @classmethod
    def error(cls, message: str, status: int = 400, **extra) -> Reply:
        return cls.json({"error": message, **extra}, status)

    def data(self) -> dict:
        """The JSON body (tests)."""
        return json.loads(self.body)


def _speed(raw) -> float:
    try:
        speed = float(raw)
    except (TypeError, ValueError):
        raise InputError("speed", raw, "a speed in m/s from 0 to 10", "the page") from None
    if not (math.isfinite(speed) and 0 <= speed <= 10):
        raise InputError("speed", raw, "a speed in m/s from 0 to 10", "the page")
    return round(speed, 1)


class App:
    """The page's work, independent of HTTP (see the module docstring).

    Parameters
    ----------
    diagnose : callable, optional
        The gap diagnosis from files (``bikerider serve`` passes
        :func:`bikerider.diagnose.diagnose_files`); without it the gap endpoints say so.
    upload_root : path, optional
        Where the private upload folder is made (default: the system's temporary folder).
    """

    def __init__(self, diagnose: Callable | None = None, upload_root: str | Path | None = None) -> None:
        self.dynamics = dynamics.Dynamics()
        self.uploads = UploadFolders(upload_root)
        self.gap = GapJobs(self.uploads, diagnose) if diagnose is not None else None

    def close(self) -> None:
        self.uploads.remove_all()

    # -- the bicycle ------------------------------------------------------------------------------
    def bicycles(self) -> Reply:
        return Reply.json({"shipped": bicycle.shipped_choices(), "speeds": [0.0, 10.0, 0.1], "limits": LIMITS})

    def _loaded(self, loaded: bicycle.LoadedBicycle) -> Reply:
        return Reply.json(
            {
                "name": loaded.name,
                "notes": loaded.notes,
                "note_fields": bicycle.notes_by_field(loaded.notes),
                "cells": bicycle.cells_of(loaded.parameters),
                "table": bicycle.parameter_table(loaded.parameters),
            }
        )

    def load_shipped(self, request: dict) -> Reply:
        return self._loaded(bicycle.load_shipped(str(request.get("id", ""))))

    def load_files(self, request: dict) -> Reply:
        folder = str(request.get("folder", ""))
        path = self.uploads.path(folder, str(request.get("bicycle", "")))
        rider = request.get("rider")
        rider_path = self.uploads.path(folder, str(rider)) if rider else None
        return self._loaded(bicycle.load_files(path, rider_path, name=Path(path).name))

    # -- every edit -------------------------------------------------------------------------------
    def _parameters(self, request: dict) -> bicycle.EditResult:
        cells = request.get("cells")
        if not isinstance(cells, dict):
            raise InputError("cells", type(cells).__name__, "the parameter table as {name: [value, sigma]}", "the page")
        steer = request.get("steer_frame")
        return bicycle.edited_parameters(cells, steer if isinstance(steer, dict) else None)

    def update(self, request: dict) -> Reply:
        """The figures' data for the table, speed and map of the page (or the errors of the table)."""
        edit = self._parameters(request)
        out = edit.as_dict()
        if edit.parameters is None:
            return Reply.json(out)
        speed = _speed(request.get("speed", 5.0))
        out["table"] = bicycle.parameter_table(edit.parameters)
        out["cells"] = bicycle.cells_of(edit.parameters)
        axes = None
        spec = request.get("map")
        if isinstance(spec, dict) and spec.get("x"):
            try:
                axes = dynamics.check_map(spec, edit.parameters)
            except InputError as exc:
                out["map_error"] = str(exc)
        gains = None
        if isinstance(request.get("gains"), dict):
            try:
                gains = dynamics.check_gains(request["gains"])
            except InputError as exc:
                out["gains_error"] = str(exc)
        figures, timing = self.dynamics.all(edit.parameters, speed, axes, gains)
        out.update(figures)
        out["speed"] = speed
        out["timing"] = timing
        out["map_axes"] = [list(a) for a in axes] if axes else None
        return Reply.json(out)

    def monte_carlo(self, request: dict) -> Reply:
        """The Monte Carlo sigmas of the weave and capsize speeds of the table (once edits pause)."""
        edit = self._parameters(request)
        if edit.parameters is None:
            return Reply.json(edit.as_dict())
        result, seconds = self.dynamics.result("monte_carlo", edit.parameters)
        return Reply.json({"ok": True, "monte_carlo": result, "timing": {"monte_carlo": round(1000 * seconds, 2)}})

    # -- downloads --------------------------------------------------------------------------------
    def _valid(self, request: dict):
        edit = self._parameters(request)
        if edit.parameters is None:
            first = next(iter(edit.errors.values()))[0]
            raise InputError("parameters", "the table", f"a table without errors ({first})", "the page")
        return edit.parameters

    def download(self, request: dict) -> Reply:
        parameters = self._valid(request)
        kind, fmt = str(request.get("kind", "")), str(request.get("format", ""))
        name = str(request.get("name", "bicycle"))
        axes = None
        spec = request.get("map")
        if isinstance(spec, dict) and spec.get("x"):
            axes = dynamics.check_map(spec, parameters)
        if kind == "parameters":
            filename, text = downloads.parameter_file(parameters, fmt, name)
            return Reply(text.encode(), downloads.PARAMETER_FORMATS[fmt], filename=filename)
        if kind == "table":
            filename, text = downloads.table_file(parameters, fmt, axes)
            return Reply(text.encode(), "text/csv", filename=filename)
        if kind in downloads.FIGURES:
            speed = _speed(request.get("speed", 5.0))
            filename, data = downloads.figure_file(parameters, kind, fmt, speed, axes, title=name)
            return Reply(data, downloads.FIGURE_FORMATS[fmt], filename=filename)
        raise InputError("download", kind, f"parameters, table or one of {', '.join(downloads.FIGURES)}", "the page")

    # -- uploads and the gap ----------------------------------------------------------------------
    def new_upload(self, request: dict) -> Reply:
        return Reply.json({"folder": self.uploads.new(str(request.get("kind", "")))})

    def upload(self, folder: str, name: str, stream, size: int) -> Reply:
        self.uploads.write(folder, name, stream, size)
        return Reply.json({"folder": folder, "files": self.uploads.files(folder)})

    def _gap(self) -> GapJobs:
        if self.gap is None:
            raise InputError("gap", "off", "a server started with the diagnosis (bikerider serve)")
        return self.gap

    def gap_run(self, request: dict) -> Reply:
        experiment, data = request.get("experiment") or [], request.get("data") or []
        if not isinstance(experiment, list) or not isinstance(data, list):
            raise InputError("experiment/data", "not lists", "lists of uploaded file names", "the page")
        job = self._gap().start(
            str(request.get("folder", "")),
            str(request.get("model", "")),
            [str(x) for x in experiment],
            [str(x) for x in data],
            bool(request.get("next", True)),
        )
        return Reply.json(job.status())

    def gap_status(self, ident: str) -> Reply:
        return Reply.json(self._gap().get(ident).status())

    def gap_figure(self, ident: str, name: str) -> Reply:
        return Reply(self._gap().figure(ident, name), "image/png")

    def gap_report(self, ident: str) -> Reply:
        return Reply(self._gap().report_zip(ident), "application/zip", filename="gap_report.zip")

    # -- the page ---------------------------------------------------------------------------------
    def static(self, name: str) -> Reply:
        if name not in STATIC:
            return Reply.error(f"no such page: {name}", 404)
        data = (resources.files("bikerider.app") / "static" / name).read_bytes()
        return Reply(data, STATIC[name])


ROUTES_POST = {
    "/api/bicycle/shipped": App.load_shipped,
    "/api/bicycle/files": App.load_files,
    "/api/update": App.update,
    "/api/monte_carlo": App.monte_carlo,
    "/api/download": App.download,
    "/api/upload/new": App.new_upload,
    "/api/gap/run": App.gap_run,
}


class Handler(BaseHTTPRequestHandler):
    """Routes requests to :class:`App` (set as the server's ``app``)."""

    server_version = "bikerider-serve"
    protocol_version = "HTTP/1.1"

    @property
    def app(self) -> App:
        return self.server.app  # type: ignore[attr-defined]

    def log_message(self, format: str, *args) -> None:  # noqa: A002 - the base class's name
        LOG.debug("%s %s", self.address_string(), format % args)

    def _send(self, reply: Reply) -> None:
        self.send_response(reply.status)
        self.send_header("Content-Type", reply.content_type)
        self.send_header("Content-Length", str(len(reply.body)))
        self.send_header("Cache-Control", "no-store")
        for key, value in {**SECURITY_HEADERS, **reply.headers}.items():
            self.send_header(key, value)
        if reply.filename:
            self.send_header("Content-Disposition", f'attachment; filename="{reply.filename}"')
        if self.close_connection:
            self.send_header("Connection", "close")
        self.end_headers()
        self.wfile.write(reply.body)

    def _host_allowed(self) -> bool:
        """Only requests for the bound address or localhost (no page of another site reaches it
        through a name that resolves here)."""
        host = (self.headers.get("Host") or "").rsplit(":", 1)[0].strip("[]").lower()
        bound = str(self.server.server_address[0]).lower()
        return host in {bound, "localhost", "127.0.0.1", "::1"} or bound in ("0.0.0.0", "::")

    def _size(self) -> int:
        try:
            return int(self.headers.get("Content-Length", ""))
        except ValueError:
            raise InputError("Content-Length", self.headers.get("Content-Length"), "the body's size in bytes") from None

    def _json(self) -> dict:
        if (self.headers.get("Content-Type") or "").split(";")[0].strip() != "application/json":
            raise InputError("Content-Type", self.headers.get("Content-Type"), "application/json")
        size = self._size()
        if not 0 <= size <= JSON_LIMIT:
            self.close_connection = True
            raise InputError("request", f"{size} bytes", f"a JSON request of at most {JSON_LIMIT} bytes")
        try:
            value = json.loads(self.rfile.read(size) or b"{}")
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise InputError("request", "not JSON", f"a JSON object ({exc})") from None
        if not isinstance(value, dict):
            raise InputError("request", type(value).__name__, "a JSON object")
        return value

    def _answer(self, work: Callable[[], Reply]) -> None:
        if not self._host_allowed():
            self.close_connection = True
            self._send(Reply.error(f"Host {self.headers.get('Host')!r} is not this server", 403))
            return
        try:
            reply = work()
        except BikeriderError as exc:
            reply = Reply.error(bicycle.error_text(exc))
        except OSError as exc:
            reply = Reply.error(bicycle.error_text(exc))
        except Exception as exc:  # a bug: the page shows it and keeps working
            LOG.exception("request %s failed", self.path)
            reply = Reply.error(f"internal error ({type(exc).__name__}: {exc}); please report it", 500)
        if reply.status >= 400 and self.command in ("POST", "PUT"):
            self.close_connection = True  # the body may not have been read: this connection ends here
        self._send(reply)

    def do_GET(self) -> None:  # noqa: N802 - the base class's name
        path = urlsplit(self.path).path
        parts = [unquote(p) for p in path.strip("/").split("/")]

        def work() -> Reply:
            if path == "/":
                return self.app.static("index.html")
            if len(parts) == 2 and parts[0] == "static":
                return self.app.static(parts[1])
            if path == "/api/bicycles":
                return self.app.bicycles()
            if len(parts) >= 3 and parts[:2] == ["api", "gap"]:
                if len(parts) == 3:
                    return self.app.gap_status(parts[2])
                if len(parts) == 5 and parts[3] == "figure":
                    return self.app.gap_figure(parts[2], parts[4])
                if len(parts) == 4 and parts[3] == "report.zip":
                    return self.app.gap_report(parts[2])
            return Reply.error(f"no such page: {path}", 404)

        self._answer(work)

    def do_POST(self) -> None:  # noqa: N802
        path = urlsplit(self.path).path
        route = ROUTES_POST.get(path)
        if route is None:
            self._answer(lambda: Reply.error(f"no such endpoint: {path}", 404))
            return
        self._answer(lambda: route(self.app, self._json()))

    def do_PUT(self) -> None:  # noqa: N802
        split = urlsplit(self.path)
        parts = split.path.strip("/").split("/")

        def work() -> Reply:
            if len(parts) != 3 or parts[:2] != ["api", "upload"]:
                return Reply.error(f"no such endpoint: {split.path}", 404)
            name = (parse_qs(split.query).get("name") or [""])[0]
            size = self._size()
            self.app.uploads.check_size(parts[2], name, size)  # before the body is read
            return self.app.upload(parts[2], name, self.rfile, size)

        self._answer(work)


def make_server(app: App, host: str = "127.0.0.1", port: int = 8050) -> ThreadingHTTPServer:
    """A server for ``app`` bound to ``host:port`` (port 0: any free port)."""
    server = ThreadingHTTPServer((host, port), Handler)
    server.daemon_threads = True
    server.app = app  # type: ignore[attr-defined]
    return server


__all__ = ["App", "Handler", "Reply", "make_server"]
