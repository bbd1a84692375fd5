"""Learn the model shipped in the package (src/rnnpb/models/set1_fast.npz).

The model a fresh install interacts with before the user has learned any: learning set 1
(patterns 1, 2 and 3, two demonstrations each, from the synthetic demonstrator with seed 0),
learned with the fast preset (``TrainConfig.fast()``, seed 0, about half a minute on one
core). Its file records the config, the seed and the data's fingerprint; run again, this
script writes the same learning on the same machine and JAX version (floating point may
differ in the last digits elsewhere).

    python scripts/train_shipped_model.py [--out src/rnnpb/models/set1_fast.npz]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import rnnpb

rnnpb.configure_xla()

from rnnpb.demonstrator import learning_set  # noqa: E402  (after the XLA setting)
from rnnpb.model import TrainConfig, train  # noqa: E402
from rnnpb.robot import JOINT_LIMITS  # noqa: E402

DEFAULT_OUT = Path(__file__).resolve().parent.parent / "src" / "rnnpb" / "models" / \
    "set1_fast.npz"
LEARNING_SET = "1"
SEED = 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    model = train(learning_set(LEARNING_SET, seed=SEED), JOINT_LIMITS,
                  config=TrainConfig.fast(seed=SEED))
    model.save(args.out)
    info = model.meta["training"]
    print(f"wrote {args.out}: patterns {', '.join(model.patterns)}, "
          f"{info['iterations']} iterations in {info['seconds']:.1f} s, "
          f"mse max {info['mse_max']:.2e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
