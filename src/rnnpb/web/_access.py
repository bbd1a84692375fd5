"""Who may use the dashboard, and what the page may load.

A page from any web site can make the browser that shows it open a WebSocket to
``127.0.0.1`` and send it commands, and a site whose name resolves to ``127.0.0.1`` (DNS
rebinding) can even read the server's answers. So the server answers only requests whose
``Host`` names it (the loopback names, the address it listens on, and the names given with
``--allow-host``), and accepts a WebSocket only from its own page or an origin given with
``--allow-origin``. Every response also carries a Content-Security-Policy that lets the page
run only the server's own script files (docs/dashboard.md).
"""

from __future__ import annotations

import ipaddress
import re
from collections.abc import Iterable
from dataclasses import dataclass
from urllib.parse import urlsplit

from rnnpb.errors import ConfigError

LOOPBACK_HOSTS = ("127.0.0.1", "localhost", "[::1]")
"""The names this computer's own browser uses for the server; always allowed."""
ANY_ADDRESS = ("", "0.0.0.0", "[::]")
"""Listening addresses that mean every interface: they name no host a browser would use."""
DEFAULT_PORTS = {"http": 80, "https": 443}

CONTENT_SECURITY_POLICY = "; ".join(
    (
        "default-src 'none'",
        "script-src 'self'",  # the page's own module files, no inline script, no eval
        "style-src 'self'",
        "img-src 'self' data:",  # the webcam frame and the empty favicon are data: URLs
        "connect-src 'self'",  # the WebSocket back to the server
        "base-uri 'none'",
        "form-action 'none'",
        "frame-ancestors 'none'",  # no other site may frame the controls (clickjacking)
    )
)
SECURITY_HEADERS = (
    ("content-security-policy", CONTENT_SECURITY_POLICY),
    ("x-content-type-options", "nosniff"),
    ("x-frame-options", "DENY"),
    ("referrer-policy", "no-referrer"),
    ("cross-origin-resource-policy", "same-origin"),
)

_NAME = re.compile(r"[a-z0-9]([a-z0-9_-]*[a-z0-9])?(\.[a-z0-9]([a-z0-9_-]*[a-z0-9])?)*\.?")


def normalize_host(name: str) -> str:
    """A host name or IP address as a ``Host`` header carries it: lower case, an IPv6
    address in brackets and compressed (``[::1]``). No port, no scheme, no wildcard."""
    if not isinstance(name, str):
        raise ConfigError(f"a host must be a name or an IP address, got {name!r:.60}")
    text = name.strip().lower()
    bare = text[1:-1] if text.startswith("[") and text.endswith("]") else text
    try:
        address = ipaddress.ip_address(bare)
    except ValueError:
        address = None
    if address is not None:
        return f"[{address.compressed}]" if address.version == 6 else address.compressed
    if len(text) > 253 or not _NAME.fullmatch(text):
        raise ConfigError(
            f"{name!r:.80} is not a host name or IP address (give the name "
            "alone, e.g. robot.lab or 192.168.1.20: no scheme, port or '*')"
        )
    return text


def normalize_origin(origin: str) -> str:
    """A web origin as ``scheme://host:port`` with the port always written, so that
    ``http://robot.lab`` and ``http://robot.lab:80`` compare equal."""
    text = origin.strip() if isinstance(origin, str) else ""
    try:
        parts = urlsplit(text)
        port = parts.port
    except ValueError:
        parts, port = None, None
    if (
        parts is None
        or parts.scheme not in DEFAULT_PORTS
        or not parts.hostname
        or parts.username is not None
        or parts.password is not None
        or parts.path not in ("", "/")
        or parts.query
        or parts.fragment
    ):
        raise ConfigError(
            f"{origin!r:.80} is not a web origin (scheme://host[:port], e.g. http://robot.lab:8765)"
        )
    host = normalize_host(parts.hostname)
    return f"{parts.scheme}://{host}:{port or DEFAULT_PORTS[parts.scheme]}"


@dataclass(frozen=True)
class AccessPolicy:
    """The ``Host`` names the server answers and the origins whose WebSocket it accepts.

    Parameters
    ----------
    hosts : tuple of str
        Host names or IP addresses answered besides :data:`LOOPBACK_HOSTS` (``--allow-host``).
        A page the server sent under one of these names, or a loopback name, may open the
        WebSocket when it reached the server on the same port.
    origins : tuple of str
        Further page origins (``scheme://host[:port]``) whose WebSocket is accepted
        (``--allow-origin``), e.g. the page behind a proxy on another port.
    """

    hosts: tuple[str, ...] = ()
    origins: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if isinstance(self.hosts, str) or isinstance(self.origins, str):
            raise ConfigError("hosts and origins must be sequences of strings, not one string")
        hosts = tuple(dict.fromkeys(normalize_host(h) for h in self.hosts))
        object.__setattr__(self, "hosts", tuple(h for h in hosts if h not in LOOPBACK_HOSTS))
        object.__setattr__(
            self, "origins", tuple(dict.fromkeys(normalize_origin(o) for o in self.origins))
        )

    @classmethod
    def for_address(
        cls, host: str, allow_hosts: Iterable[str] = (), allow_origins: Iterable[str] = ()
    ) -> AccessPolicy:
        """The policy of a server listening on ``host``: that name is answered too, unless
        it means every interface (``0.0.0.0``, ``::``), which names no host."""
        named = normalize_host(host) if host.strip() else ""
        extra = () if named in ANY_ADDRESS else (named,)
        return cls(hosts=(*extra, *allow_hosts), origins=tuple(allow_origins))

    @property
    def allowed_hosts(self) -> tuple[str, ...]:
        """Every ``Host`` name answered, in the form ``TrustedHostMiddleware`` compares."""
        return (*LOOPBACK_HOSTS, *self.hosts)

    def origin_allowed(self, origin: str | None, host_header: str | None) -> bool:
        """Whether a WebSocket handshake with this ``Origin`` may open.

        A handshake with no ``Origin`` is not from a web page (browsers always send one):
        scripts and tests may connect, as they may send any HTTP request. ``null`` (a
        ``file://`` page, a sandboxed frame) is refused. Otherwise the origin must be listed
        in :attr:`origins`, or be ``http`` on an allowed host and on the port the request
        reached (``host_header``): the server's own page.
        """
        if origin is None:
            return True
        try:
            wanted = normalize_origin(origin)
        except ConfigError:
            return False
        if wanted in self.origins:
            return True
        scheme, _, rest = wanted.partition("://")
        name, _, port = rest.rpartition(":")
        return (
            scheme == "http" and name in self.allowed_hosts and port == str(_port_of(host_header))
        )


def _port_of(host_header: str | None) -> int | None:
    try:
        return urlsplit(f"//{host_header}").port or DEFAULT_PORTS["http"]
    except ValueError:
        return None


class SecurityHeadersMiddleware:
    """Adds :data:`SECURITY_HEADERS` to every HTTP response (ASGI middleware)."""

    def __init__(self, app) -> None:
        self.app = app

    async def __call__(self, scope, receive, send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return

        async def send_with_headers(message) -> None:
            if message["type"] == "http.response.start":
                present = {k.lower() for k, _ in message.get("headers", [])}
                headers = list(message.get("headers", []))
                headers += [
                    (k.encode(), v.encode())
                    for k, v in SECURITY_HEADERS
                    if k.encode() not in present
                ]
                message = {**message, "headers": headers}
            await send(message)

        await self.app(scope, receive, send_with_headers)
