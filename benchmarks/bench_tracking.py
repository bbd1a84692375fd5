"""Colour-ball tracking speed at 640x480 on one core, and centre accuracy on rendered frames.

Run: ``.venv/bin/python benchmarks/bench_tracking.py [--frames N]``
"""

from __future__ import annotations

import argparse
import platform

from rnnpb.perception import tracking_benchmark


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=500, help="timed frames (default 500)")
    args = parser.parse_args()
    f = tracking_benchmark(n_frames=args.frames)
    print(
        f"colour-ball tracking, {f['width']}x{f['height']}, one core "
        f"({platform.processor() or platform.machine()})"
    )
    print(f"  frames timed        {f['frames']}")
    print(f"  median per frame    {f['median_ms']:.2f} ms  ({f['fps']:.0f} frames/s)")
    print(f"  90th percentile     {f['p90_ms']:.2f} ms")
    print(f"  centre error, clean frames               {f['clean_error_px']:.2f} px mean")
    print(
        f"  centre error, noise + blur + clutter     {f['noisy_error_px']:.2f} px mean, "
        f"{f['noisy_p95_px']:.2f} px 95th percentile"
    )
    print(f"  balls reported for the wrong hand        {f['swapped']}")


if __name__ == "__main__":
    main()
