"""``rnnpb serve``: the live dashboard in the browser."""

from __future__ import annotations

import argparse

NAME = "serve"
HELP = "open the live dashboard: watch the robot imitate the demonstrator, your mouse or webcam"
DESCRIPTION = """\
Start a local web page that shows the simulated humanoid in 3-D, driven live by the synthetic
demonstrator (patterns 1-4, switch, pause), by you dragging two hand markers with the mouse or
a touch screen, or by the webcam with the colour-ball tracker. Live plots show the perceived
and predicted hands, the joint angles and the parametric bias moving towards the learned
pattern it recognises. The session can be downloaded as CSV.

Serves on 127.0.0.1 (this computer only) unless --host says otherwise. All tabs share one
session. Stop with Ctrl-C.

Examples:
  rnnpb serve --model models/set1.npz
  rnnpb serve --model models/ --port 9000 --dt 0.2
  rnnpb serve --model models/ --host 0.0.0.0      # reachable from other machines
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--model", default="models", metavar="MODEL_OR_DIR",
                        help="a trained model (.npz) or a folder searched for *.npz "
                             "(default: models)")
    parser.add_argument("--host", default="127.0.0.1",
                        help="address to listen on (default 127.0.0.1: this computer only)")
    parser.add_argument("--port", type=int, default=8765, help="port (default 8765; 0: any free)")
    parser.add_argument("--dt", type=float, default=0.4,
                        help="seconds per network step (default 0.4, as in the paper; "
                             "changeable on the page)")
    parser.add_argument("--log-level", default="warning",
                        choices=("debug", "info", "warning", "error"),
                        help="server log detail (default warning)")


def run(args: argparse.Namespace) -> int:
    import logging

    from rnnpb.errors import ConfigError
    from rnnpb.web import DashboardServer, find_models
    from rnnpb.web._protocol import MAX_DT, MIN_DT

    if not MIN_DT <= args.dt <= MAX_DT:
        raise ConfigError(f"--dt must be in [{MIN_DT}, {MAX_DT}] seconds, got {args.dt}")
    if not 0 <= args.port <= 65535:
        raise ConfigError(f"--port must be in [0, 65535], got {args.port}")
    logging.basicConfig(level=args.log_level.upper(), format="%(levelname)s %(name)s: %(message)s")
    models = find_models(args.model)
    server = DashboardServer(models, host=args.host, port=args.port, dt=args.dt,
                             log_level=args.log_level)
    server.start()
    print(f"rnnpb dashboard: {server.url}  (models: {', '.join(models)}; Ctrl-C to stop)",
          flush=True)
    try:
        server.wait()
    finally:
        server.stop()
    return 0
