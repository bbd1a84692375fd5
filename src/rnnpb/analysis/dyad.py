"""The measures of mutual interaction (the paper's section 4.2), computed from arrays.

Two agents — two robots, or a robot and a subject — each move their hands; each agent's
movement is taken in the *person's* sensory space (``lhy lhz rhy rhz`` as a robot's camera
sees a person; a robot's body is mapped there by :mod:`rnnpb.interaction.dyad`). Definitions:

* **movement class** of an agent at step t: over the last ``window`` steps (one cycle), its
  trajectory with each coordinate's mean removed is compared with every ``window``-step stretch
  of each learned pattern's *references* (each stretch's mean removed): the pattern *as taught*
  (one cycle of the demonstrator's ideal movement at every phase, :func:`movement_templates`)
  and, for a robot, the pattern *as its network plays it* (its closed-loop generation from the
  pattern's learned PB, :func:`rnnpb.interaction.person_space.pattern_references`). The class is the
  pattern of the best-fitting stretch if its RMS misfit is below ``tolerance`` times that
  stretch's RMS and the agent moves (some coordinate's spread above ``MOVING_LEVEL``); else
  none (``""``: still, or no learned movement). It is judged from what the agent does, never
  from what it reports (its PB, its intent);
* **phase lock** at step t: over the last ``window`` steps, the normalised cross-correlation of
  the two agents' movements (means removed, the four coordinates together) at lags of at most
  ``max_lag`` steps (the agents see each other one step late, so a follower is a step or two
  behind); locked where the best correlation is at least ``LOCK_CORRELATION`` at each of the
  last ``LOCK_STEADY`` steps and its lag stayed within one step of the present one — a stable
  phase relation, not one chance alignment;
* **synchrony error** at step t (reported, not part of coherence): RMS difference of the two
  agents' recent trajectories, minimised over the same lags;
* **coherent** at step t (joint attention): both agents' movement classes are the same learned
  pattern and they are phase-locked;
* **joint-attention episode**: a run of at least ``min_steps`` coherent steps (gaps shorter
  than ``bridge`` steps do not end it), with its pattern, start and duration;
* **shifts**: a *pattern shift* is an episode followed by an episode on another pattern; a
  *phase shift* is each change between the coherent and the incoherent phase (episode start or
  end);
* **who leads a shift**: the agent whose movement class changed to the new episode's pattern
  first (the other followed); ties are ``""``; the **leader index** of a run is
  (shifts led by A − shifts led by B) / shifts, in [−1, 1];
* **transfer entropy** ``TE(x → y)``: in bits, of the binned series, history of one step at
  ``lag``; on the agents' PB changes it says whose changes predict the other's;
* **patterns found** over time (the subject protocol): a learned pattern is found when the
  first episode on it has lasted ``min_steps``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rnnpb.demonstrator import PATTERNS, PatternConfig, pattern_offsets
from rnnpb.robot.camera import RobotCamera

CLASS_WINDOW = 12  # one cycle of the demonstrator's patterns
CLASS_TOLERANCE = 0.5
SYNC_TOLERANCE = 0.03
MAX_LAG = 2
LOCK_CORRELATION = 0.8  # cross-correlation of the two movements at their best lag
LOCK_STEADY = 6  # steps (half a cycle) over which the lag must hold
MIN_EPISODE = 12
BRIDGE = 3
MOVING_LEVEL = 0.02  # view units: below this spread over a cycle, an agent is still


def movement_templates(
    patterns: tuple[str, ...] = PATTERNS,
    period: int = 12,
    config: PatternConfig | None = None,
    camera: RobotCamera | None = None,
) -> dict[str, np.ndarray]:
    """One cycle of each pattern as the robot's camera sees a person do it, ``period`` steps,
    each of shape (period, 4), each coordinate's mean removed."""
    config = config or PatternConfig()
    camera = camera or RobotCamera()
    theta = 2 * np.pi * np.arange(period) / period
    out = {}
    for name in patterns:
        views = camera.sensory_from_hands(
            config.body.hand_centres + pattern_offsets(name, theta, config)
        )
        out[name] = views - views.mean(axis=0)
    return out


@dataclass(frozen=True)
class MovementClass:
    """Per step: the pattern (``""`` for none), its best phase (the template step aligned with
    the last step; -1 where the best fit is a stretch of a closed-loop reference or none) and
    the relative RMS misfit. Arrays of shape (n,)."""

    pattern: np.ndarray
    phase: np.ndarray
    misfit: np.ndarray


def _windows(views: np.ndarray, window: int) -> np.ndarray:
    """Every ``window``-step stretch of (T, 4), each coordinate's mean removed: (T-window+1,
    window, 4)."""
    stretches = np.lib.stride_tricks.sliding_window_view(views, window, axis=0)
    stretches = np.moveaxis(stretches, -1, 1)  # (T - window + 1, window, 4)
    return stretches - stretches.mean(axis=1, keepdims=True)


def _reference_bank(
    templates: dict[str, np.ndarray],
    references: dict[str, np.ndarray] | None,
    window: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every stretch the movement class compares with: (M, window*4) stretches, (M,) pattern
    names, (M,) phase (template step, -1 for a reference trajectory's stretch)."""
    rows, names, phases = [], [], []
    for name, cycle in templates.items():
        k = len(cycle)
        # The template's step j aligned with the stretch's last step, every j (periodic).
        index = (np.arange(k)[:, None] + np.arange(-window + 1, 1)[None, :]) % k
        stretches = cycle[index]
        stretches = stretches - stretches.mean(axis=1, keepdims=True)
        rows.append(stretches.reshape(k, -1))
        names += [name] * k
        phases += list(range(k))
    for name, trajectory in (references or {}).items():
        trajectory = np.asarray(trajectory, dtype=np.float64)
        if len(trajectory) < window or not np.isfinite(trajectory).all():
            continue
        stretches = _windows(trajectory, window)
        rows.append(stretches.reshape(len(stretches), -1))
        names += [name] * len(stretches)
        phases += [-1] * len(stretches)
    return np.concatenate(rows), np.array(names, dtype=object), np.array(phases)


def classify_movement(
    views: np.ndarray,
    templates: dict[str, np.ndarray],
    window: int = CLASS_WINDOW,
    tolerance: float = CLASS_TOLERANCE,
    references: dict[str, np.ndarray] | None = None,
) -> MovementClass:
    """The movement class of each step (see the module's definitions).

    Parameters
    ----------
    views : array, shape (n, 4)
        The agent's hands in the person's sensory space; NaN where not known.
    templates : dict name -> array (K, 4)
        One cycle of each pattern as taught, mean removed (:func:`movement_templates`).
    references : dict name -> array (T, 4), optional
        More of each pattern: a trajectory (e.g. a robot's closed-loop generation of it, seen
        as its partner sees it), every ``window``-step stretch of which is compared too.
    """
    views = np.asarray(views, dtype=np.float64)
    n = len(views)
    pattern = np.full(n, "", dtype=object)
    phase = np.full(n, -1, dtype=np.int64)
    misfit = np.full(n, np.inf)
    if n < window:
        return MovementClass(pattern=pattern, phase=phase, misfit=misfit)
    bank, names, phases = _reference_bank(templates, references, window)
    scale = np.sqrt(np.mean(bank**2, axis=1))  # (M,)
    segments = _windows(views, window).reshape(n - window + 1, -1)  # (N, D)
    finite = np.isfinite(segments).all(axis=1)
    segments = np.where(finite[:, None], segments, 0.0)
    squared = (
        np.sum(segments**2, axis=1)[:, None]
        + np.sum(bank**2, axis=1)[None, :]
        - 2.0 * segments @ bank.T
    )
    with np.errstate(divide="ignore", invalid="ignore"):
        fits = np.sqrt(np.maximum(squared, 0.0) / segments.shape[1]) / scale[None, :]
    fits = np.where(np.isfinite(fits), fits, np.inf)
    best = np.argmin(fits, axis=1)
    best_fit = fits[np.arange(len(best)), best]
    best_fit = np.where(finite, best_fit, np.inf)
    misfit[window - 1 :] = best_fit
    hit = best_fit < tolerance
    at = np.arange(window - 1, n)[hit]
    pattern[at] = names[best[hit]]
    phase[at] = phases[best[hit]]
    return MovementClass(pattern=pattern, phase=phase, misfit=misfit)


@dataclass(frozen=True)
class PhaseLock:
    """Per step: ``locked`` (bool), the best ``lag`` (steps B is behind A; negative: A is
    behind) and the cross-correlation ``correlation`` at that lag. Arrays of shape (n,)."""

    locked: np.ndarray
    lag: np.ndarray
    correlation: np.ndarray


def phase_lock(
    a: np.ndarray,
    b: np.ndarray,
    window: int = CLASS_WINDOW,
    max_lag: int = MAX_LAG,
    min_correlation: float = LOCK_CORRELATION,
    steady: int = LOCK_STEADY,
) -> PhaseLock:
    """The phase lock of two agents' movements, (n, 4) each (see the module's definitions);
    from past steps only."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    n = len(a)
    lag = np.zeros(n, dtype=np.int64)
    best = np.full(n, np.nan)
    locked = np.zeros(n, dtype=bool)
    if n < window + max_lag:
        return PhaseLock(locked, lag, best)

    def normalised(views: np.ndarray) -> np.ndarray:
        stretches = _windows(views, window).reshape(n - window + 1, -1)
        norm = np.linalg.norm(stretches, axis=1, keepdims=True)
        with np.errstate(divide="ignore", invalid="ignore"):
            out = stretches / norm
        return np.where(np.isfinite(out), out, 0.0)  # still or unknown: no correlation

    wa, wb = normalised(a), normalised(b)  # row i: the stretch ending at step i + window - 1
    lags = np.arange(-max_lag, max_lag + 1)
    first = max_lag  # rows from which every lag has its past stretch
    rows = np.arange(first, len(wa))
    correlations = np.empty((len(rows), len(lags)))
    for k, ell in enumerate(lags):
        if ell >= 0:  # B now against A ``ell`` steps back: A leads
            correlations[:, k] = np.sum(wa[rows - ell] * wb[rows], axis=1)
        else:
            correlations[:, k] = np.sum(wa[rows] * wb[rows + ell], axis=1)
    k_best = np.argmax(correlations, axis=1)
    steps = rows + window - 1
    lag[steps] = lags[k_best]
    best[steps] = correlations[np.arange(len(rows)), k_best]
    good = np.nan_to_num(best, nan=-1.0) >= min_correlation
    for t in steps[steps >= steps[0] + steady - 1]:
        span = slice(t - steady + 1, t + 1)
        locked[t] = bool(good[span].all() and np.all(np.abs(lag[span] - lag[t]) <= 1))
    return PhaseLock(locked=locked, lag=lag, correlation=best)


def synchrony_error(
    a: np.ndarray, b: np.ndarray, window: int = CLASS_WINDOW, max_lag: int = MAX_LAG
) -> np.ndarray:
    """Per step, the RMS difference of the two agents' last ``window`` steps, minimised over
    lags ``-max_lag … max_lag``; NaN before enough steps or where a value is NaN. (n,)"""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    n = len(a)
    out = np.full(n, np.nan)
    for t in range(window - 1 + max_lag, n):
        now = slice(t - window + 1, t + 1)
        errors = []
        for lag in range(max_lag + 1):  # only steps up to t: the other one ``lag`` steps back
            then = slice(t - window + 1 - lag, t + 1 - lag)
            errors.append(np.sqrt(np.mean((a[then] - b[now]) ** 2)))
            errors.append(np.sqrt(np.mean((a[now] - b[then]) ** 2)))
        finite = [e for e in errors if np.isfinite(e)]
        if finite:
            out[t] = min(finite)
    return out


def coherence(
    class_a: np.ndarray,
    class_b: np.ndarray,
    locked: np.ndarray,
    learned: tuple[str, ...],
) -> np.ndarray:
    """Per step, True where both agents move the same learned pattern, phase-locked. (n,)"""
    class_a = np.asarray(class_a, dtype=object)
    class_b = np.asarray(class_b, dtype=object)
    same = (class_a == class_b) & np.isin(class_a, list(learned))
    return same & np.asarray(locked, dtype=bool)


@dataclass(frozen=True)
class Episode:
    """A joint-attention episode: steps ``start`` … ``end - 1`` on ``pattern``."""

    start: int
    end: int
    pattern: str

    @property
    def duration(self) -> int:
        return self.end - self.start


def episodes(
    coherent: np.ndarray,
    joint_pattern: np.ndarray,
    min_steps: int = MIN_EPISODE,
    bridge: int = BRIDGE,
) -> list[Episode]:
    """The joint-attention episodes of a run (see the module's definitions).

    ``joint_pattern`` (n,) names the pattern at each coherent step (e.g. agent A's class); an
    episode takes the pattern most of its steps had.
    """
    coherent = np.asarray(coherent, dtype=bool)
    joint_pattern = np.asarray(joint_pattern, dtype=object)
    runs: list[list[int]] = []
    t, n = 0, len(coherent)
    while t < n:
        if not coherent[t]:
            t += 1
            continue
        start = t
        while t < n and coherent[t]:
            t += 1
        # A short gap on the same pattern continues the run.
        if (
            runs
            and start - runs[-1][1] < bridge
            and joint_pattern[start] == joint_pattern[runs[-1][1] - 1]
        ):
            runs[-1][1] = t
        else:
            runs.append([start, t])
    out = []
    for start, end in runs:
        if end - start < min_steps:
            continue
        names, counts = np.unique(
            [p for p, c in zip(joint_pattern[start:end], coherent[start:end], strict=False) if c],
            return_counts=True,
        )
        out.append(Episode(start, end, str(names[int(np.argmax(counts))])))
    return out


@dataclass(frozen=True)
class Shift:
    """A pattern shift: joint attention moved from ``before`` to ``after``; the new episode
    started at ``step``; ``leader`` is ``"a"``, ``"b"`` or ``""`` (a tie or unknown);
    ``lead`` the steps by which the leader's movement changed first."""

    step: int
    before: str
    after: str
    leader: str
    lead: int


def shift_leader(
    class_a: np.ndarray, class_b: np.ndarray, start: int, pattern: str, since: int
) -> tuple[str, int]:
    """Which agent's movement class became ``pattern`` first within ``since … start``
    (the last change to it before the new episode's start), and by how many steps."""

    def onset(classes: np.ndarray) -> int | None:
        classes = np.asarray(classes, dtype=object)
        t = min(start, len(classes) - 1)
        if classes[t] != pattern:
            return None
        while t > since and classes[t - 1] == pattern:
            t -= 1
        return t

    on_a, on_b = onset(class_a), onset(class_b)
    if on_a is None or on_b is None or on_a == on_b:
        return "", 0
    return ("a", on_b - on_a) if on_a < on_b else ("b", on_a - on_b)


def pattern_shifts(found: list[Episode], class_a: np.ndarray, class_b: np.ndarray) -> list[Shift]:
    """The pattern shifts between consecutive episodes, each with its leader."""
    out = []
    for previous, current in zip(found, found[1:], strict=False):
        if previous.pattern == current.pattern:
            continue
        leader, lead = shift_leader(
            class_a, class_b, current.start, current.pattern, previous.end - 1
        )
        out.append(Shift(current.start, previous.pattern, current.pattern, leader, lead))
    return out


def phase_shifts(coherent: np.ndarray, found: list[Episode]) -> int:
    """Changes between the coherent and the incoherent phase: each episode's start (unless the
    run starts coherent) and end (unless the run ends in it)."""
    n = len(coherent)
    return sum(int(e.start > 0) + int(e.end < n) for e in found)


def leader_index(shifts: list[Shift]) -> float:
    """(shifts led by A − shifts led by B) / shifts; NaN without shifts."""
    if not shifts:
        return float("nan")
    return (sum(s.leader == "a" for s in shifts) - sum(s.leader == "b" for s in shifts)) / len(
        shifts
    )


def transfer_entropy(source: np.ndarray, target: np.ndarray, bins: int = 3, lag: int = 1) -> float:
    """TE(source → target) in bits: how much the source's value ``lag`` steps back tells about
    the target's next value beyond the target's own last value. Each series is binned into
    ``bins`` equally filled bins (a few bins: the runs are short). (n,) each."""
    x = np.asarray(source, dtype=np.float64)
    y = np.asarray(target, dtype=np.float64)
    keep = np.isfinite(x) & np.isfinite(y)
    x, y = x[keep], y[keep]
    if len(x) <= lag + 2:
        return float("nan")

    def binned(v: np.ndarray) -> np.ndarray:
        edges = np.quantile(v, np.linspace(0, 1, bins + 1)[1:-1])
        return np.searchsorted(edges, v, side="right")

    xb, yb = binned(x), binned(y)
    y_next, y_now, x_then = yb[lag:], yb[lag - 1 : -1], xb[:-lag]
    joint = np.zeros((bins, bins, bins))
    np.add.at(joint, (y_next, y_now, x_then), 1.0)
    joint /= joint.sum()
    p_now_then = joint.sum(axis=0)  # (y_now, x_then)
    p_next_now = joint.sum(axis=2)  # (y_next, y_now)
    p_now = joint.sum(axis=(0, 2))  # (y_now,)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = joint * p_now[None, :, None] / (p_next_now[:, :, None] * p_now_then[None])
        terms = np.where(joint > 0, joint * np.log2(ratio), 0.0)
    return float(terms.sum())


def pb_change(pb: np.ndarray) -> np.ndarray:
    """How far the PB moved each step (Euclidean), (n,); the first step is 0."""
    pb = np.asarray(pb, dtype=np.float64)
    out = np.zeros(len(pb))
    out[1:] = np.linalg.norm(np.diff(pb, axis=0), axis=1)
    return out


def patterns_found(
    found: list[Episode], n_steps: int, learned: tuple[str, ...], min_steps: int = MIN_EPISODE
) -> np.ndarray:
    """How many of the learned patterns had been found by each step (n_steps,): a pattern is
    found at the step its first episode became one (``min_steps`` coherent steps)."""
    out = np.zeros(n_steps, dtype=np.int64)
    seen: set[str] = set()
    for episode in sorted(found, key=lambda e: e.start):
        if episode.pattern in learned and episode.pattern not in seen:
            seen.add(episode.pattern)
            out[min(episode.start + min_steps, n_steps) - 1 :] = len(seen)
    return out


@dataclass(frozen=True)
class DyadMeasures:
    """Every measure of one two-agent run (see the module's definitions).

    Arrays have shape (n,): ``class_a``/``class_b`` movement classes, ``sync_error``,
    ``lock`` (:class:`PhaseLock`), ``coherent``, ``found`` (patterns found by each step).
    """

    class_a: np.ndarray
    class_b: np.ndarray
    sync_error: np.ndarray
    lock: PhaseLock
    coherent: np.ndarray
    episodes: list[Episode]
    shifts: list[Shift]
    phase_shifts: int
    found: np.ndarray
    coherent_share: float
    first_coherent: int | None
    leader_index: float
    te_a_to_b: float
    te_b_to_a: float

    def summary(self, dt: float = 0.4) -> dict[str, float | int | None]:
        """The run's scalar measures; rates per simulated minute at ``dt`` seconds a step."""
        minutes = len(self.coherent) * dt / 60.0
        sync = self.sync_error[self.coherent]
        return {
            "steps": len(self.coherent),
            "coherent_share": self.coherent_share,
            "first_coherent": self.first_coherent,
            "locked_share": float(self.lock.locked.mean()) if len(self.coherent) else 0.0,
            "sync_error_coherent": float(np.nanmedian(sync)) if sync.size else float("nan"),
            "episodes": len(self.episodes),
            "mean_episode_steps": (
                float(np.mean([e.duration for e in self.episodes])) if self.episodes else 0.0
            ),
            "pattern_shifts": len(self.shifts),
            "shifts_per_minute": len(self.shifts) / minutes if minutes > 0 else 0.0,
            "phase_shifts": self.phase_shifts,
            "led_by_a": sum(s.leader == "a" for s in self.shifts),
            "led_by_b": sum(s.leader == "b" for s in self.shifts),
            "leader_index": self.leader_index,
            "te_a_to_b": self.te_a_to_b,
            "te_b_to_a": self.te_b_to_a,
            "patterns_found": int(self.found[-1]) if len(self.found) else 0,
        }


def moving(
    views: np.ndarray, window: int = CLASS_WINDOW, level: float = MOVING_LEVEL
) -> np.ndarray:
    """Per step, True where some coordinate's standard deviation over the last ``window``
    steps exceeds ``level`` (view units); False where a value is unknown. (n,)"""
    views = np.asarray(views, dtype=np.float64)
    out = np.zeros(len(views), dtype=bool)
    if len(views) < window:
        return out
    stretches = _windows(views, window)
    spread = np.sqrt(np.mean(stretches**2, axis=1))  # (N, 4)
    with np.errstate(invalid="ignore"):
        out[window - 1 :] = np.isfinite(spread).all(axis=1) & (spread.max(axis=1) > level)
    return out


def measure_dyad(
    view_a: np.ndarray,
    view_b: np.ndarray,
    learned: tuple[str, ...],
    pb_a: np.ndarray | None = None,
    pb_b: np.ndarray | None = None,
    templates: dict[str, np.ndarray] | None = None,
    min_episode: int = MIN_EPISODE,
    references_a: dict[str, np.ndarray] | None = None,
    references_b: dict[str, np.ndarray] | None = None,
) -> DyadMeasures:
    """All measures of a run from the two agents' movements in the person's sensory space,
    (n, 4) each, and their PBs (n, P) where they have one (the transfer entropy is on their
    PB changes; without PBs, on how often their movement class changes).

    ``templates``: each pattern as taught (default: the demonstrator's,
    :func:`movement_templates`); ``references_a``/``references_b``: each agent's own playing
    of its learned patterns (name -> (T, 4), e.g. a robot's closed loop,
    :func:`rnnpb.interaction.person_space.pattern_references`), compared as well."""
    templates = templates or movement_templates()
    ca = np.where(
        moving(view_a), classify_movement(view_a, templates, references=references_a).pattern, ""
    ).astype(object)
    cb = np.where(
        moving(view_b), classify_movement(view_b, templates, references=references_b).pattern, ""
    ).astype(object)
    sync = synchrony_error(view_a, view_b)
    lock = phase_lock(view_a, view_b)
    coherent_steps = coherence(ca, cb, lock.locked, learned)
    found = episodes(coherent_steps, ca, min_steps=min_episode)
    shifts = pattern_shifts(found, ca, cb)
    change_a = pb_change(pb_a) if pb_a is not None else _class_changes(ca)
    change_b = pb_change(pb_b) if pb_b is not None else _class_changes(cb)
    first = np.flatnonzero(coherent_steps)
    return DyadMeasures(
        class_a=ca,
        class_b=cb,
        sync_error=sync,
        lock=lock,
        coherent=coherent_steps,
        episodes=found,
        shifts=shifts,
        phase_shifts=phase_shifts(coherent_steps, found),
        found=patterns_found(found, len(coherent_steps), learned, min_episode),
        coherent_share=float(coherent_steps.mean()) if len(coherent_steps) else 0.0,
        first_coherent=int(first[0]) if first.size else None,
        leader_index=leader_index(shifts),
        te_a_to_b=transfer_entropy(change_a, change_b),
        te_b_to_a=transfer_entropy(change_b, change_a),
    )


def _class_changes(classes: np.ndarray) -> np.ndarray:
    classes = np.asarray(classes, dtype=object)
    out = np.zeros(len(classes))
    out[1:] = classes[1:] != classes[:-1]
    return out
