"""The live dashboard (``rnnpb serve``): a local web page that shows the simulated humanoid
imitating the demonstrator, the mouse or the webcam, with live plots of the hands, the joint
angles and the parametric bias (docs/dashboard.md)."""

from rnnpb.web._access import CONTENT_SECURITY_POLICY, LOOPBACK_HOSTS, AccessPolicy
from rnnpb.web._broadcast import RECENT_STEPS
from rnnpb.web._models import find_models, offered_models
from rnnpb.web._protocol import (
    MAX_DT,
    MAX_MESSAGE_BYTES,
    MIN_DT,
    TEACH_MODES,
    ProtocolError,
    parse_client_message,
)
from rnnpb.web._recording import RecordingLimits
from rnnpb.web._server import (
    STATIC_DIR,
    WS_MAX_SIZE,
    CommandLimits,
    DashboardServer,
    create_app,
)
from rnnpb.web._session import Session
from rnnpb.web._sources import DemonstratorSource, PointerSource
from rnnpb.web._teaching import TeachingSettings
from rnnpb.web._thread import MAX_QUEUED_COMMANDS

__all__ = [
    "CONTENT_SECURITY_POLICY",
    "LOOPBACK_HOSTS",
    "MAX_DT",
    "MAX_MESSAGE_BYTES",
    "MAX_QUEUED_COMMANDS",
    "MIN_DT",
    "RECENT_STEPS",
    "STATIC_DIR",
    "TEACH_MODES",
    "WS_MAX_SIZE",
    "AccessPolicy",
    "CommandLimits",
    "DashboardServer",
    "DemonstratorSource",
    "PointerSource",
    "ProtocolError",
    "RecordingLimits",
    "Session",
    "TeachingSettings",
    "create_app",
    "find_models",
    "offered_models",
    "parse_client_message",
]
