"""The ``--perception`` option of the commands that read a camera (``track``, ``record``,
``interact``, ``serve``)."""

from __future__ import annotations

import argparse

PERCEPTION_CHOICES = ("balls", "pose")
"""As :data:`rnnpb.perception.PERCEPTIONS` (kept here so that building the parser imports no
camera code)."""


def add_perception_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--perception",
        choices=PERCEPTION_CHOICES,
        default="balls",
        help="how a camera's frames become the hands: balls (a coloured ball on each hand, the "
        "default) or pose (bare hands through a pose model; needs pip install 'rnnpb[hands]')",
    )
