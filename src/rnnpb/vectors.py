"""Names and sizes of the vectors every part of rnnpb exchanges (see docs/design.md).

The sensory vector ``u`` holds the user's two hand centres in the robot camera's view plane,
normalized to [0, 1]; the motor vector ``r`` holds the robot's eight arm joint angles in radians
(normalized to [0, 1] by the joint limits only at the network's boundary).
"""

SENSORY_NAMES: tuple[str, ...] = ("lhy", "lhz", "rhy", "rhz")
MOTOR_NAMES: tuple[str, ...] = (
    "lshp",
    "lshr",
    "lshy",
    "lelp",
    "rshp",
    "rshr",
    "rshy",
    "relp",
)
SENSORY_SIZE = len(SENSORY_NAMES)
MOTOR_SIZE = len(MOTOR_NAMES)
STEP_COLUMN = "step"
PREDICTED_PREFIX = "pred_"
TRUTH_PATTERN_COLUMN = "truth_pattern"
PB_PREFIX = "pb"


def pb_column(unit: int) -> str:
    """The column of PB unit ``unit`` in a session recording: ``pb0``, ``pb1``, …"""
    return f"{PB_PREFIX}{unit}"
