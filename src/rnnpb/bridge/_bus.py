"""Opening the Zenoh bus: spec strings (``zenoh:KEY@ENDPOINT``) and the session's config.

Zenoh is imported when a session is opened, not when rnnpb is. A session runs in peer mode:
two processes talk directly, no router. Without an endpoint the peers find each other by
Zenoh's multicast scouting (its default, on the local network); with ``@ENDPOINT`` one side
listens there (``rnnpb robot serve --listen``) and the other connects, and scouting is off so
that only the named peer is reached. ``ZENOH_CONFIG=FILE`` starts from a Zenoh config file
(routers, TLS, ...).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any

from rnnpb.errors import ConfigError


def import_zenoh() -> Any:
    """The ``zenoh`` module; a one-line error naming what to install when it is missing."""
    try:
        import zenoh
    except ImportError:
        raise ConfigError(
            "the Zenoh bridge needs the eclipse-zenoh package: pip install 'eclipse-zenoh>=1.10,<2'"
        ) from None
    return zenoh


@dataclass(frozen=True)
class BusConfig:
    """Where this process's Zenoh peer listens and whom it connects to (endpoints such as
    ``tcp/127.0.0.1:7447``); both empty: Zenoh's own discovery."""

    connect: tuple[str, ...] = ()
    listen: tuple[str, ...] = ()

    def open(self) -> Any:
        """A new Zenoh session (peer mode)."""
        zenoh = import_zenoh()
        path = os.environ.get("ZENOH_CONFIG")
        config = zenoh.Config.from_file(path) if path else zenoh.Config()
        try:
            config.insert_json5("mode", '"peer"')
            if self.connect or self.listen:
                config.insert_json5("scouting/multicast/enabled", "false")
            if self.connect:
                config.insert_json5("connect/endpoints", json.dumps(list(self.connect)))
            if self.listen:
                config.insert_json5("listen/endpoints", json.dumps(list(self.listen)))
            return zenoh.open(config)
        except zenoh.ZError as error:
            where = ", ".join(self.listen + self.connect) or "the default endpoints"
            raise ConfigError(f"cannot open the Zenoh bus on {where}: {error}") from None


def parse_bus_spec(text: str, default_key: str, what: str) -> tuple[str, BusConfig]:
    """``"zenoh:KEY@ENDPOINT"`` (both parts optional) → the key and a config that connects to
    the endpoint. ``what`` names the option for messages."""
    kind, _, rest = text.partition(":")
    if kind.strip().lower() != "zenoh":
        raise ConfigError(f"{what} {text!r}: expected zenoh[:KEY][@ENDPOINT]")
    key, at, endpoint = rest.partition("@")
    key = key.strip().strip("/") or default_key
    if any(c in key for c in "*$?#") or "//" in key:
        raise ConfigError(f"{what} {text!r}: {key!r} is not a plain Zenoh key (no wildcards)")
    if at and not endpoint.strip():
        raise ConfigError(f"{what} {text!r}: an endpoint follows @, e.g. @tcp/127.0.0.1:7447")
    return key, BusConfig(connect=(endpoint.strip(),) if endpoint.strip() else ())
