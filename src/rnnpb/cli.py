"""The ``rnnpb`` command.

Each subcommand lives in ``rnnpb/commands/<name>.py`` and defines ``NAME``, ``HELP``,
``DESCRIPTION``, ``add_arguments(parser)`` and ``run(args) -> int``. Command modules import
heavy libraries (JAX, MuJoCo, OpenCV) inside ``run`` only, so ``rnnpb --help`` stays fast.

The command line makes the process-wide choices a library leaves to its user: before anything
imports JAX it applies rnnpb's XLA setting (:func:`rnnpb.configure_xla`; ``RNNPB_XLA_DEFAULTS=0``
keeps XLA's defaults). A command that sets ``SAFE_POINTS = True`` runs with
:class:`rnnpb._interrupt.SafeInterrupts`: Ctrl-C stops it at the next point it checks, never in
the middle of an import or an XLA compilation, and it exits 130 (see docs/robustness.md).
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from rnnpb import __version__, _interrupt, _xla
from rnnpb.errors import RnnpbError

# The order here is the order in `rnnpb --help`.
COMMAND_MODULES: tuple[str, ...] = (
    "rnnpb.commands.demo",
    "rnnpb.commands.study",
    "rnnpb.commands.sweep",
    "rnnpb.commands.train",
    "rnnpb.commands.train_routines",
    "rnnpb.commands.consolidate",
    "rnnpb.commands.info",
    "rnnpb.commands.presets",
    "rnnpb.commands.generate",
    "rnnpb.commands.interact",
    "rnnpb.commands.robot",
    "rnnpb.commands.data",
    "rnnpb.commands.record",
    "rnnpb.commands.memory",
    "rnnpb.commands.track",
    "rnnpb.commands.calibrate",
    "rnnpb.commands.cameras",
    "rnnpb.commands.serve",
    "rnnpb.commands.view",
    "rnnpb.commands.bench",
    "rnnpb.commands.safety",
)


def _available_commands():
    for name in COMMAND_MODULES:
        try:
            yield importlib.import_module(name)
        except ModuleNotFoundError as error:
            if error.name != name:
                raise


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="rnnpb",
        description=(
            "A humanoid robot learns movement patterns from demonstrations with a recurrent "
            "neural network with parametric bias (RNNPB), then imitates a person on-line: it "
            "recognises the person's movement and moves in synchrony with it (Ito & Tani 2004)."
        ),
        epilog="Run `rnnpb COMMAND --help` for a command's options.",
    )
    parser.add_argument("--version", action="version", version=f"rnnpb {__version__}")
    parser.add_argument(
        "--debug",
        action="store_true",
        help="show the full traceback of an error instead of one line",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in _available_commands():
        command = sub.add_parser(
            module.NAME,
            help=module.HELP,
            description=module.DESCRIPTION,
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        module.add_arguments(command)
        command.set_defaults(
            _run=module.run, _safe_points=bool(getattr(module, "SAFE_POINTS", False))
        )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    interrupts = _interrupt.safe_interrupts()
    args = argparse.Namespace(debug=False)
    try:
        # From the start: a Ctrl-C while the command line starts is held like one in a command.
        with interrupts:
            # Before any command imports JAX: XLA reads its flags once, when its backend starts.
            _xla.configure()
            _xla.compilation_cache()  # compiled programs kept for the next process
            parser = build_parser()
            args = parser.parse_args(argv)
            if not getattr(args, "_run", None):
                parser.print_help()
                return 2
            interrupts.check()
            if args._safe_points:
                status = int(args._run(args) or 0)
                if interrupts.requested:
                    # Ctrl-C after the command's last safe point: its output is complete.
                    interrupts.requested = False
                    print(
                        "rnnpb: interrupted after the work was done; the output is complete",
                        file=sys.stderr,
                    )
                return status
        # A command without safe points: Python's own Ctrl-C, caught below.
        return int(args._run(args) or 0)
    except RnnpbError as error:
        if args.debug:
            raise
        print(f"rnnpb: error: {error}", file=sys.stderr)
        return 2
    except OSError as error:
        # The system refused a file or device (permissions, a full disk): the user can act on
        # that, so it is reported like an RnnpbError.
        if args.debug:
            raise
        where = f"{error.filename}: " if error.filename else ""
        print(f"rnnpb: error: {where}{error.strerror or error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("rnnpb: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
