"""The dashboard's web server: a Starlette app served by uvicorn.

Routes: ``/`` the page, ``/game`` the mirror game (its WebSocket ``/ws/game``; docs/dashboard.md),
``/static/…`` its files (all vendored, nothing is fetched from the
internet), ``/api/state`` the session state as JSON, ``/api/recording.csv`` the current
session recording, and ``/ws`` the WebSocket every tab opens (docs/dashboard.md). Requests
whose ``Host`` the :class:`AccessPolicy` does not name get 400, WebSocket handshakes from a
foreign page get 403, and every response carries the page's Content-Security-Policy.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import threading
import time
from dataclasses import dataclass
from pathlib import Path

from starlette.applications import Starlette
from starlette.middleware import Middleware
from starlette.middleware.trustedhost import TrustedHostMiddleware
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, PlainTextResponse, Response
from starlette.routing import Mount, Route, WebSocketRoute
from starlette.staticfiles import StaticFiles
from starlette.websockets import WebSocket, WebSocketDisconnect

from rnnpb.web._access import ANY_ADDRESS, AccessPolicy, SecurityHeadersMiddleware, normalize_host
from rnnpb.web._game import GameSession
from rnnpb.web._protocol import ProtocolError, parse_client_message
from rnnpb.web._recording import RecordingLimits
from rnnpb.web._session import Session
from rnnpb.web._teaching import TeachingSettings

log = logging.getLogger("rnnpb.web")

STATIC_DIR = Path(__file__).parent / "static"
SEND_QUEUE = 256
"""Messages kept for a slow client; beyond that its oldest are dropped, never the robot's
steps slowed down."""
WS_MAX_SIZE = 65536
"""WebSocket frames larger than this are refused by the protocol layer itself (close code
1009); smaller ones over the message limit get an error reply."""


@dataclass(frozen=True)
class CommandLimits:
    """How many messages one connection may send (token buckets: ``rate`` a second on
    average, ``burst`` at once). A message beyond them gets an error reply and is dropped,
    so a flood costs the robot nothing but the parsing.

    Attributes
    ----------
    commands_per_s, command_burst : float
        Control messages (start, stop, reset, mode, pattern, dt, model, camera): each is
        applied by the session thread between two steps, and a reset or a model change
        starts a new recording. A person clicking fast sends a few a second.
    hands_per_s, hands_burst : float
        Pointer positions and pings, answered in place: the page sends at most one per
        animation frame (60 a second), two fingers included.
    """

    commands_per_s: float = 10.0
    command_burst: float = 20.0
    hands_per_s: float = 120.0
    hands_burst: float = 120.0


class _TokenBucket:
    def __init__(self, rate: float, burst: float) -> None:
        self.rate, self.burst = float(rate), float(burst)
        self.tokens = self.burst
        self.last = time.monotonic()

    def take(self) -> bool:
        now = time.monotonic()
        self.tokens = min(self.burst, self.tokens + (now - self.last) * self.rate)
        self.last = now
        if self.tokens < 1.0:
            return False
        self.tokens -= 1.0
        return True


def create_app(
    session: Session,
    access: AccessPolicy | None = None,
    limits: CommandLimits | None = None,
    games_dir: str | Path | None = None,
) -> Starlette:
    """The ASGI app serving ``session`` (already started) to the hosts and origins
    ``access`` allows (default: this computer's loopback names only), each connection within
    ``limits`` (default :class:`CommandLimits`); the game's logs go to ``games_dir`` (default:
    ``games`` in the session's folder)."""
    access = access or AccessPolicy()
    limits = limits or CommandLimits()

    async def index(request: Request) -> Response:
        return FileResponse(STATIC_DIR / "index.html", media_type="text/html")

    async def state(request: Request) -> Response:
        return JSONResponse(session.state())

    async def recording(request: Request) -> Response:
        path = session.recording_path
        if path is None or not path.exists():
            return PlainTextResponse(
                "no session recorded yet: start the robot first", status_code=404
            )
        name = f"rnnpb-{(session.model_name or 'session').replace('/', '_')}-{path.name}"
        return FileResponse(path, media_type="text/csv", filename=name)

    async def websocket(ws: WebSocket) -> None:
        client = f"{ws.client.host}:{ws.client.port}" if ws.client else "client"
        origin = ws.headers.get("origin")
        if not access.origin_allowed(origin, ws.headers.get("host")):
            # A page from another site, run by a browser here, must not drive the robot nor
            # receive the camera's frames.
            log.warning(
                "%s: refused a WebSocket from origin %.200r (allowed: this server's "
                "own page; more with --allow-origin)",
                client,
                origin,
            )
            await ws.send_denial_response(
                PlainTextResponse(
                    f"origin {origin!r:.200} may not use this dashboard (start rnnpb serve with "
                    "--allow-origin to allow it)\n",
                    status_code=403,
                )
            )
            return
        await ws.accept()
        loop = asyncio.get_running_loop()
        outbox: asyncio.Queue[str] = asyncio.Queue(maxsize=SEND_QUEUE)

        def put(text: str) -> None:
            if outbox.full():
                outbox.get_nowait()
            outbox.put_nowait(text)

        def from_session(text: str) -> None:
            with contextlib.suppress(RuntimeError):  # the event loop is closing
                loop.call_soon_threadsafe(put, text)

        async def sender() -> None:
            while True:
                await ws.send_text(await outbox.get())

        commands = _TokenBucket(limits.commands_per_s, limits.command_burst)
        light = _TokenBucket(limits.hands_per_s, limits.hands_burst)
        # The state and the run's recent steps first, so a new tab starts with full plots.
        unsubscribe = session.subscribe(from_session, replay=True)
        sending = asyncio.create_task(sender())
        log.info("%s connected (%d watching)", client, session.subscriber_count)
        try:
            while True:
                event = await ws.receive()
                if event["type"] == "websocket.disconnect":
                    break
                try:
                    message = parse_client_message(event.get("text", event.get("bytes")))
                except ProtocolError as error:
                    log.warning("%s: rejected message: %s", client, error)
                    put(json.dumps({"type": "error", "message": f"rejected: {error}"}))
                    continue
                except Exception:  # a gap in the checks: still an answer, never a dropped tab
                    log.exception("%s: message not checked", client)
                    put(
                        json.dumps(
                            {
                                "type": "error",
                                "message": "rejected: the server could not check this message",
                            }
                        )
                    )
                    continue
                kind = message["type"]
                if not (light if kind in ("hands", "ping") else commands).take():
                    what = (
                        f"at most {limits.hands_per_s:g} hands or ping messages"
                        if kind in ("hands", "ping")
                        else f"at most {limits.commands_per_s:g} commands"
                    )
                    put(
                        json.dumps(
                            {
                                "type": "error",
                                "message": f"rejected: too many "
                                f"messages ({what} a second); {kind} dropped",
                            }
                        )
                    )
                elif kind == "hands":
                    session.pointer.set_hands(message["hands"])
                elif kind == "ping":
                    put('{"type":"pong"}')
                elif not session.submit(message):
                    put(
                        json.dumps(
                            {
                                "type": "error",
                                "message": "rejected: the session has "
                                f"too many commands waiting; {kind} dropped",
                            }
                        )
                    )
        except WebSocketDisconnect:
            pass
        finally:
            unsubscribe()
            sending.cancel()
            with contextlib.suppress(asyncio.CancelledError, WebSocketDisconnect, RuntimeError):
                await sending
            log.info("%s disconnected", client)

    games = Path(games_dir) if games_dir is not None else session.workdir / "games"
    game = GameSession(session.models, dt=session.dt, log_dir=games)

    async def game_page(request: Request) -> Response:
        return FileResponse(STATIC_DIR / "game.html", media_type="text/html")

    async def game_log(request: Request) -> Response:
        """The log of the last game (``/game/log.json`` or ``/game/log.csv``)."""
        kind = request.path_params["kind"]
        current = game.log
        if current is None or kind not in ("json", "csv"):
            return PlainTextResponse("no game has been played yet\n", status_code=404)
        path = current.json_path if kind == "json" else current.csv_path
        return FileResponse(
            path,
            media_type="application/json" if kind == "json" else "text/csv",
            filename=path.name,
        )

    async def game_socket(ws: WebSocket) -> None:
        """The mirror game's WebSocket: the same origin rule and message checks as ``/ws``."""
        if not access.origin_allowed(ws.headers.get("origin"), ws.headers.get("host")):
            await ws.send_denial_response(
                PlainTextResponse("this origin may not use this dashboard\n", status_code=403)
            )
            return
        await ws.accept()
        loop = asyncio.get_running_loop()
        outbox: asyncio.Queue[str] = asyncio.Queue(maxsize=SEND_QUEUE)

        def put(text: str) -> None:
            if outbox.full():
                outbox.get_nowait()
            outbox.put_nowait(text)

        def from_game(text: str) -> None:
            with contextlib.suppress(RuntimeError):
                loop.call_soon_threadsafe(put, text)

        async def sender() -> None:
            while True:
                await ws.send_text(await outbox.get())

        put(json.dumps(game.state()))
        unsubscribe = game.subscribe(from_game)
        sending = asyncio.create_task(sender())
        try:
            while True:
                event = await ws.receive()
                if event["type"] == "websocket.disconnect":
                    break
                try:
                    message = parse_client_message(event.get("text", event.get("bytes")))
                    if message["type"] not in ("game", "game_hands", "ping"):
                        raise ProtocolError(
                            f"the game page does not take {message['type']!r} messages"
                        )
                except ProtocolError as error:
                    put(json.dumps({"type": "error", "message": f"rejected: {error}"}))
                    continue
                if message["type"] == "ping":
                    put('{"type":"pong"}')
                elif message["type"] == "game":
                    # Starting loads a model and compiles: not on the event loop.
                    await asyncio.to_thread(game.submit, message)
                else:
                    game.submit(message)
        except WebSocketDisconnect:
            pass
        finally:
            unsubscribe()
            sending.cancel()
            with contextlib.suppress(asyncio.CancelledError, WebSocketDisconnect, RuntimeError):
                await sending

    routes = [
        Route("/", index),
        Route("/game", game_page),
        Route("/game/log.{kind}", game_log),
        WebSocketRoute("/ws/game", game_socket),
        Route("/api/state", state),
        Route("/api/recording.csv", recording),
        WebSocketRoute("/ws", websocket),
        Mount("/static", StaticFiles(directory=STATIC_DIR), name="static"),
    ]
    middleware = [
        Middleware(SecurityHeadersMiddleware),
        # Refuses DNS rebinding: a foreign name that resolves here reaches the server with
        # its own name in Host.
        Middleware(
            TrustedHostMiddleware, allowed_hosts=list(access.allowed_hosts), www_redirect=False
        ),
    ]
    app = Starlette(routes=routes, middleware=middleware)
    app.state.game = game
    return app


class DashboardServer:
    """The session and its web server on ``host:port``, run in a background thread.

    It answers requests for the loopback names and for ``host`` (unless ``host`` is a
    listen-everywhere address such as ``0.0.0.0``), and for the names in ``allow_hosts``; its
    WebSocket accepts its own page and the origins in ``allow_origins`` (:class:`AccessPolicy`).

    >>> with DashboardServer(models, port=0) as server:    # doctest: +SKIP
    ...     print(server.url)
    """

    def __init__(
        self,
        models: dict[str, Path],
        host: str = "127.0.0.1",
        port: int = 8765,
        dt: float = 0.4,
        model: str | None = None,
        workdir: str | Path | None = None,
        log_level: str = "warning",
        allow_hosts: tuple[str, ...] = (),
        allow_origins: tuple[str, ...] = (),
        limits: CommandLimits | None = None,
        recording_limits: RecordingLimits | None = None,
        teaching: TeachingSettings | None = None,
        games_dir: str | Path | None = None,
    ) -> None:
        import uvicorn

        self.access = AccessPolicy.for_address(host, allow_hosts, allow_origins)
        self.session = Session(
            models,
            dt=dt,
            workdir=workdir,
            recording_limits=recording_limits,
            teaching=teaching,
        )
        self._first_model = model
        # The game's logs are the person's: kept in ``games/`` of the folder the server was
        # started in, never in the session's temporary folder (deleted when it stops).
        self.games_dir = Path(games_dir) if games_dir is not None else Path.cwd() / "games"
        self.app = create_app(self.session, self.access, limits, self.games_dir)
        config = uvicorn.Config(
            self.app,
            host=host,
            port=port,
            log_level=log_level,
            ws="websockets-sansio",
            ws_max_size=WS_MAX_SIZE,
            lifespan="off",
        )
        self.server = uvicorn.Server(config)
        self.host = host
        self._thread: threading.Thread | None = None

    @property
    def port(self) -> int:
        servers = getattr(self.server, "servers", None)
        if servers:
            return servers[0].sockets[0].getsockname()[1]
        return self.server.config.port

    @property
    def url(self) -> str:
        """The page's address; on a listen-everywhere address, the loopback one (a browser
        asking for ``0.0.0.0`` names no host the server answers)."""
        host = normalize_host(self.host) if self.host.strip() else ""
        if host in ANY_ADDRESS:
            host = "[::1]" if host == "[::]" else "127.0.0.1"
        return f"http://{host}:{self.port}/"

    def start(self) -> DashboardServer:
        import time

        from rnnpb.errors import RnnpbError

        self.session.start(self._first_model)
        self._thread = threading.Thread(target=self.server.run, name="rnnpb-web", daemon=True)
        self._thread.start()
        deadline = time.monotonic() + 10
        while not self.server.started:
            if not self._thread.is_alive() or time.monotonic() > deadline:
                self.app.state.game.stop()
                self.session.close()
                raise RnnpbError(
                    f"cannot serve on {self.host}:{self.server.config.port} (is the port in use?)"
                )
            time.sleep(0.02)
        return self

    def stop(self) -> None:
        self.server.should_exit = True
        if self._thread is not None:
            self._thread.join(timeout=10)
        self.app.state.game.stop()
        self.session.close()

    def wait(self) -> None:
        """Block until the server stops (Ctrl-C stops it; so does SIGTERM, which a service
        manager sends, when waiting on the main thread: the caller's cleanup then runs)."""
        import signal

        def terminate(signum: int, frame: object) -> None:
            raise KeyboardInterrupt

        previous = None
        if threading.current_thread() is threading.main_thread():
            previous = signal.signal(signal.SIGTERM, terminate)
        try:
            if self._thread is not None:
                while self._thread.is_alive():
                    self._thread.join(timeout=0.5)
        finally:
            if previous is not None:
                signal.signal(signal.SIGTERM, previous)

    def __enter__(self) -> DashboardServer:
        return self.start()

    def __exit__(self, *exc_info: object) -> None:
        self.stop()
