"""The synthetic camera: renders the user, with a coloured ball on each hand, as the robot's
head camera (:class:`rnnpb.robot.camera.RobotCamera`) would see them.

The ball on each hand is drawn as a shaded disk at the projection of the hand position, with
the apparent radius of a sphere of ``ball_radius_m`` at its depth, anti-aliased at sub-pixel
precision; the user's body (torso, head, arms reaching to the hands) in clothes and skin
colours; a background wall with texture and clutter whose colours stay clear of the balls'
(unless ``distractors`` asks for red and blue objects). Per frame: lighting changes, pixel
noise, motion blur and occluders that hide a ball now and then — each a parameter of
:class:`SceneConfig`, all drawn from the seed, so a frame is the same however it is reached.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import cv2
import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.perception._sources import FrameSource
from rnnpb.robot.camera import RobotCamera

_SHIFT = 4  # fractional bits for cv2 drawing at sub-pixel precision
_ONE = 1 << _SHIFT


@dataclass(frozen=True)
class SceneConfig:
    """What the synthetic camera draws.

    Attributes
    ----------
    ball_radius_m : float
        Radius of the balls on the hands, metres.
    left_ball_bgr, right_ball_bgr : (int, int, int)
        Ball colours (default saturated red on the left hand, blue on the right).
    body : bool
        Draw the user's torso, head and arms.
    clutter : int
        Number of random shapes on the background wall (0: a plain wall).
    texture : float
        Amplitude (in grey levels) of the wall's low-frequency texture.
    lighting : float
        Per-frame relative change of brightness (gain drawn in 1 ± lighting, plus a gradient of
        the same size across the image).
    noise_sigma : float
        Standard deviation of the per-pixel Gaussian noise, grey levels.
    blur_probability : float
        Probability that a frame has motion blur.
    blur_px : float
        Longest motion-blur streak, pixels (a centred line kernel in a random direction).
    occlusion_probability : float
        Per frame and ball, the probability that an occluder starts hiding the ball.
    occlusion_frames : (int, int)
        Range of an occlusion's length in frames.
    occlusions : tuple of (hand, start, stop)
        Occlusions at fixed frames (hand 0 = left, 1 = right; frames start…stop-1), in
        addition to the random ones.
    distractors : int
        Number of small red and blue objects (not round) on the wall, to test robustness.
    static_distractors : int
        Objects of the balls' colours and sizes that stay put, away from the hands' path, in
        turn: a dark-blue book, a dark-red book (rectangles about as big as a ball), a blue and a
        red round object (shaded like the balls, 0.8-1.25 times their radius).
    moving_distractors : int
        Objects of the balls' colours and sizes that cross the wall on straight lines, each
        entering at a random frame, in turn: a blue round object, a red book, a red round
        object, a blue book. They pass behind the user (the hands and arms hide them).
    flicker : float
        Amplitude of a periodic change of brightness from frame to frame (mains lighting beating
        against the frame rate), on top of ``lighting``.
    seed : int
    """

    ball_radius_m: float = 0.04
    left_ball_bgr: tuple[int, int, int] = (35, 30, 205)
    right_ball_bgr: tuple[int, int, int] = (195, 70, 30)
    body: bool = True
    clutter: int = 40
    texture: float = 18.0
    lighting: float = 0.08
    noise_sigma: float = 4.0
    blur_probability: float = 0.2
    blur_px: float = 9.0
    occlusion_probability: float = 0.01
    occlusion_frames: tuple[int, int] = (3, 8)
    occlusions: tuple[tuple[int, int, int], ...] = ()
    distractors: int = 0
    static_distractors: int = 0
    moving_distractors: int = 0
    flicker: float = 0.0
    seed: int = 0

    def __post_init__(self) -> None:
        if not self.ball_radius_m > 0:
            raise ConfigError(f"scene ball_radius_m must be > 0, got {self.ball_radius_m}")
        for name in ("clutter", "distractors", "static_distractors", "moving_distractors"):
            if getattr(self, name) < 0:
                raise ConfigError(f"scene {name} must be >= 0, got {getattr(self, name)}")
        for name in ("texture", "lighting", "noise_sigma", "blur_px", "flicker"):
            if not getattr(self, name) >= 0:
                raise ConfigError(f"scene {name} must be >= 0, got {getattr(self, name)}")
        for name in ("blur_probability", "occlusion_probability"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ConfigError(f"scene {name} must be in [0, 1], got {getattr(self, name)}")
        low, high = self.occlusion_frames
        if not 1 <= low <= high:
            raise ConfigError(
                f"scene occlusion_frames must be 1 <= low <= high, got {self.occlusion_frames}"
            )
        for item in self.occlusions:
            if len(item) != 3 or item[0] not in (0, 1) or not 0 <= item[1] <= item[2]:
                raise ConfigError(f"scene occlusions: {item!r} is not (hand 0|1, start, stop)")

    @classmethod
    def clean(cls, **changes: Any) -> SceneConfig:
        """The user on a plain wall: no clutter, noise, lighting change, blur or occlusion."""
        base = cls(
            clutter=0,
            texture=0.0,
            lighting=0.0,
            noise_sigma=0.0,
            blur_probability=0.0,
            occlusion_probability=0.0,
        )
        return replace(base, **changes)

    @classmethod
    def hard(cls, **changes: Any) -> SceneConfig:
        """Heavy clutter, noise, lighting change and frequent blur."""
        base = cls(
            clutter=80,
            texture=25.0,
            lighting=0.15,
            noise_sigma=8.0,
            blur_probability=0.5,
            blur_px=12.0,
        )
        return replace(base, **changes)


def _bgr_from_hsv(h: float, s: float, v: float) -> tuple[int, int, int]:
    pixel = np.array([[[h, s, v]]], dtype=np.uint8)
    b, g, r = cv2.cvtColor(pixel, cv2.COLOR_HSV2BGR)[0, 0]
    return int(b), int(g), int(r)


def _neutral_color(rng: np.random.Generator) -> tuple[int, int, int]:
    """A background colour far from saturated red and blue."""
    if rng.random() < 0.5:  # desaturated, any hue
        return _bgr_from_hsv(rng.integers(0, 180), rng.integers(0, 70), rng.integers(40, 240))
    # saturated but yellow…green…cyan: hue 18…90
    return _bgr_from_hsv(rng.integers(18, 91), rng.integers(70, 256), rng.integers(60, 240))


def _pt(p: np.ndarray) -> tuple[int, int]:
    return int(round(p[0] * _ONE)), int(round(p[1] * _ONE))


class SyntheticCamera(FrameSource):
    """A camera source that renders a hand trajectory.

    Parameters
    ----------
    hands : array, shape (n_steps, 2, 3)
        The user's left (index 0) and right (index 1) hand positions in the robot frame, metres;
        the balls sit on them.
    camera : RobotCamera, optional
    scene : SceneConfig, optional
    truth : dict, optional
        Extra ground truth copied into every frame's ``last_truth`` (e.g. the pattern name).

    After each ``read``, ``last_truth`` holds ``sensory`` (4,), ``center_px`` (2, 2),
    ``radius_px`` (2,), ``visible_fraction`` (2,) and ``occluded`` (2,) for the frame.
    """

    def __init__(
        self,
        hands: np.ndarray,
        camera: RobotCamera | None = None,
        scene: SceneConfig | None = None,
        truth: dict[str, Any] | None = None,
    ) -> None:
        super().__init__()
        hands = np.asarray(hands, dtype=np.float64)
        if hands.ndim != 3 or hands.shape[1:] != (2, 3) or len(hands) == 0:
            raise ConfigError(
                f"synthetic camera: hands must have shape (n_steps, 2, 3), got {hands.shape}"
            )
        if not np.all(np.isfinite(hands)):
            raise ConfigError("synthetic camera: hands contain NaN or infinite values")
        self.hands = hands
        self.camera = camera or RobotCamera()
        self.scene = scene or SceneConfig()
        self.extra_truth = dict(truth or {})
        self.description = f"synthetic camera ({len(hands)} frames, seed {self.scene.seed})"
        cam = self.camera
        self._centers, depth = cam.project(hands)  # (n, 2, 2), (n, 2)
        if np.any(depth <= 0.05):
            raise ConfigError("synthetic camera: a hand is behind or at the camera")
        self._depth = depth
        self._radii = cam.apparent_radius_px(depth, self.scene.ball_radius_m)
        self._occluded = self._occlusion_schedule()
        self._background: np.ndarray | None = None
        self._body = self._body_geometry()
        self._movers = self._moving_distractor_paths()

    def __len__(self) -> int:
        return len(self.hands)

    # --- the FrameSource interface -------------------------------------------------------
    def connect(self) -> None:
        if self._background is None:
            self._background = self._render_background()

    def read(self) -> np.ndarray | None:
        if self.frame_index + 1 >= len(self.hands):
            return None
        frame, truth = self.render(self.frame_index + 1)
        self.frame_index += 1
        self.last_truth = truth
        return frame

    # --- rendering ------------------------------------------------------------------------
    def render(self, t: int) -> tuple[np.ndarray, dict[str, Any]]:
        """Frame ``t`` (BGR uint8) and its ground truth; the same for the same seed and ``t``."""
        self.connect()
        assert self._background is not None
        scene = self.scene
        rng = np.random.default_rng([scene.seed, 1, t])
        frame = self._background.copy()
        for mover in self._movers:
            self._draw_mover(frame, mover, t)
        if scene.body:
            self._draw_body(frame, t)
        centers, radii = self._centers[t], self._radii[t]
        order = np.argsort(-self._depth[t])  # farther ball first
        colors = (scene.left_ball_bgr, scene.right_ball_bgr)
        for i in order:
            _draw_ball(frame, centers[i], radii[i], colors[i])
        occluders = []
        for i in (0, 1):
            if self._occluded[t, i]:
                occluders.append(self._draw_occluder(frame, centers[i], radii[i], rng))
        visible = self._visible_fraction(t, order, occluders)
        frame = self._degrade(frame, rng, t)
        truth = {
            **self.extra_truth,
            "frame": t,
            "sensory": self.camera.normalize_pixels(centers).reshape(4),
            "center_px": centers.copy(),
            "radius_px": radii.copy(),
            "depth_m": self._depth[t].copy(),
            "visible_fraction": visible,
            "occluded": self._occluded[t].copy(),
        }
        return frame, truth

    def _occlusion_schedule(self) -> np.ndarray:
        scene, n = self.scene, len(self.hands)
        occluded = np.zeros((n, 2), dtype=bool)
        rng = np.random.default_rng([scene.seed, 2])
        if scene.occlusion_probability > 0:
            starts = rng.random((n, 2)) < scene.occlusion_probability
            lengths = rng.integers(
                scene.occlusion_frames[0], scene.occlusion_frames[1] + 1, size=(n, 2)
            )
            for t, i in zip(*np.nonzero(starts), strict=True):
                occluded[t : t + lengths[t, i], i] = True
        for hand, start, stop in scene.occlusions:
            occluded[start:stop, hand] = True
        return occluded

    def _render_background(self) -> np.ndarray:
        cam, scene = self.camera, self.scene
        rng = np.random.default_rng([scene.seed, 0])
        wall = np.array(
            _bgr_from_hsv(rng.integers(10, 40), rng.integers(10, 50), rng.integers(150, 210)),
            dtype=np.float32,
        )
        frame = np.empty((cam.height, cam.width, 3), np.float32)
        frame[:] = wall
        if scene.texture > 0:
            coarse = rng.standard_normal((cam.height // 40 + 2, cam.width // 40 + 2, 1))
            fine = rng.standard_normal((cam.height // 6 + 2, cam.width // 6 + 2, 1))
            grain = cv2.resize(
                coarse.astype(np.float32), (cam.width, cam.height), interpolation=cv2.INTER_CUBIC
            ) + 0.4 * cv2.resize(
                fine.astype(np.float32), (cam.width, cam.height), interpolation=cv2.INTER_LINEAR
            )
            frame += scene.texture * grain[..., None]
        # the floor: the lower quarter, darker
        floor_row = int(cam.height * rng.uniform(0.72, 0.82))
        frame[floor_row:] *= 0.65
        image = np.clip(frame, 0, 255).astype(np.uint8)
        for _ in range(scene.clutter):
            self._draw_clutter(image, rng)
        for k in range(scene.distractors):
            color = (scene.left_ball_bgr, scene.right_ball_bgr)[k % 2]
            x, y = rng.uniform(0, cam.width), rng.uniform(0, cam.height)
            w, h = rng.uniform(4, 12), rng.uniform(25, 60)
            box = ((float(x), float(y)), (float(w), float(h)), float(rng.uniform(0, 180)))
            cv2.fillPoly(image, [np.round(cv2.boxPoints(box)).astype(np.int32)], color, cv2.LINE_AA)
        self._draw_static_distractors(image, rng)
        return image

    def _distractor_look(
        self, k: int, rng: np.random.Generator
    ) -> tuple[str, tuple[int, int, int], float]:
        """Kind ("book" or "round"), colour and size (radius, px) of distractor ``k``."""
        scene = self.scene
        kind = ("book", "round")[(k // 2) % 2]
        base = (scene.right_ball_bgr, scene.left_ball_bgr)[k % 2]
        hsv = cv2.cvtColor(np.array([[base]], np.uint8), cv2.COLOR_BGR2HSV)[0, 0].astype(float)
        if kind == "book":  # a darker cover, still inside the ball's default colour range
            hsv[1] *= rng.uniform(0.85, 1.0)
            hsv[2] *= rng.uniform(0.45, 0.75)
        else:
            hsv[0] = (hsv[0] + rng.uniform(-3, 3)) % 180
            hsv[2] *= rng.uniform(0.8, 1.0)
        color = _bgr_from_hsv(*hsv)
        radius = float(np.median(self._radii)) * rng.uniform(0.8, 1.25)
        return kind, color, radius

    def _draw_static_distractors(self, image: np.ndarray, rng: np.random.Generator) -> None:
        cam = self.camera
        path = self._centers.reshape(-1, 2)
        reach = float(self._radii.max())
        for k in range(self.scene.static_distractors):
            kind, color, radius = self._distractor_look(k, rng)
            for _ in range(200):  # away from where the hands go: a look-alike, not an overlap
                c = np.array(
                    [
                        rng.uniform(radius, cam.width - radius),
                        rng.uniform(radius, cam.height - radius),
                    ]
                )
                if np.min(np.linalg.norm(path - c, axis=1)) > 2.0 * (reach + radius):
                    break
            else:
                continue
            _draw_distractor(image, kind, c, radius, color, float(rng.uniform(-15, 15)))

    def _moving_distractor_paths(self) -> list[dict[str, Any]]:
        cam, scene, n = self.camera, self.scene, len(self.hands)
        rng = np.random.default_rng([scene.seed, 3])
        movers = []
        for k in range(scene.moving_distractors):
            look_rng = np.random.default_rng([scene.seed, 4, k])
            kind, color, radius = self._distractor_look((2, 1, 3, 0)[k % 4], look_rng)
            start = int(rng.integers(0, max(1, n // 2)))
            y0, y1 = rng.uniform(0.1, 0.9, size=2) * cam.height
            x0, x1 = (-2 * radius, cam.width + 2 * radius)[:: (1 if rng.random() < 0.5 else -1)]
            speed = rng.uniform(3.0, 9.0)
            steps = max(1, int(math.hypot(x1 - x0, y1 - y0) / speed))
            movers.append(
                {
                    "kind": kind,
                    "color": color,
                    "radius": radius,
                    "start": start,
                    "steps": steps,
                    "from": np.array([x0, y0]),
                    "to": np.array([x1, y1]),
                    "angle": float(rng.uniform(-20, 20)),
                }
            )
        return movers

    def _draw_mover(self, frame: np.ndarray, mover: dict[str, Any], t: int) -> None:
        s = (t - mover["start"]) / mover["steps"]
        if not 0.0 <= s <= 1.0:
            return
        center = (1 - s) * mover["from"] + s * mover["to"]
        _draw_distractor(
            frame, mover["kind"], center, mover["radius"], mover["color"], mover["angle"]
        )

    def _draw_clutter(self, image: np.ndarray, rng: np.random.Generator) -> None:
        h, w = image.shape[:2]
        color = _neutral_color(rng)
        kind = rng.integers(0, 4)
        x, y = int(rng.integers(0, w)), int(rng.integers(0, h))
        size = int(rng.integers(10, 90))
        if kind == 0:
            cv2.rectangle(image, (x, y), (x + size, y + int(rng.integers(10, 90))), color, -1)
        elif kind == 1:
            cv2.circle(image, (x, y), size // 2, color, -1, cv2.LINE_AA)
        elif kind == 2:
            cv2.ellipse(
                image,
                (x, y),
                (size // 2, int(rng.integers(5, 40))),
                float(rng.uniform(0, 180)),
                0,
                360,
                color,
                -1,
                cv2.LINE_AA,
            )
        else:
            cv2.line(
                image,
                (x, y),
                (x + int(rng.integers(-120, 120)), y + int(rng.integers(-120, 120))),
                color,
                int(rng.integers(2, 8)),
                cv2.LINE_AA,
            )

    def _body_geometry(self) -> dict[str, np.ndarray]:
        hands = self.hands
        # the user's arms reach forward to the hands: shoulders behind and above them
        x = float(np.median(hands[..., 0])) + 0.3
        y = float(np.mean(hands[..., 1]))
        z = float(np.median(hands[..., 2])) + 0.2
        half = 0.19
        # the user's left shoulder is on the robot's right (negative y)
        return {
            "shoulders": np.array([[x, y - half, z], [x, y + half, z]]),
            "hips": np.array([[x, y - 0.15, z - 0.55], [x, y + 0.15, z - 0.55]]),
            "neck": np.array([x, y, z + 0.05]),
            "head": np.array([x, y, z + 0.22]),
        }

    def _draw_body(self, frame: np.ndarray, t: int) -> None:
        cam, body = self.camera, self._body
        skin, shirt, hair = (140, 170, 210), (105, 118, 88), (45, 50, 55)
        shoulders, _ = cam.project(body["shoulders"])
        hips, _ = cam.project(body["hips"])
        torso = np.array([shoulders[0], shoulders[1], hips[1], hips[0]])
        cv2.fillPoly(
            frame, [np.round(torso * _ONE).astype(np.int32)], shirt, cv2.LINE_AA, shift=_SHIFT
        )
        (head,), (head_depth,) = cam.project(body["head"][None])
        head_r = cam.focal_px * 0.095 / head_depth
        neck, _ = cam.project(body["neck"][None])
        cv2.line(
            frame,
            _pt(neck[0]),
            _pt(head),
            skin,
            max(2, int(head_r * 0.8)),
            cv2.LINE_AA,
            shift=_SHIFT,
        )
        cv2.ellipse(
            frame,
            _pt(head),
            (int(head_r * 0.85 * _ONE), int(head_r * 1.1 * _ONE)),
            0,
            0,
            360,
            skin,
            -1,
            cv2.LINE_AA,
            shift=_SHIFT,
        )
        cv2.ellipse(
            frame,
            _pt(head - [0, head_r * 0.35]),
            (int(head_r * 0.9 * _ONE), int(head_r * 0.8 * _ONE)),
            0,
            180,
            360,
            hair,
            -1,
            cv2.LINE_AA,
            shift=_SHIFT,
        )
        for i in (0, 1):
            shoulder = body["shoulders"][i]
            hand = self.hands[t, i]
            outward = np.sign(shoulder[1] - body["neck"][1])
            elbow = 0.5 * (shoulder + hand) + np.array([0.06, 0.06 * outward, -0.08])
            pts, depth = cam.project(np.stack([shoulder, elbow, hand]))
            width = cam.focal_px * 0.09 / depth
            cv2.line(
                frame,
                _pt(pts[0]),
                _pt(pts[1]),
                shirt,
                max(2, int(width[0])),
                cv2.LINE_AA,
                shift=_SHIFT,
            )
            cv2.line(
                frame,
                _pt(pts[1]),
                _pt(pts[2]),
                skin,
                max(2, int(width[1] * 0.75)),
                cv2.LINE_AA,
                shift=_SHIFT,
            )

    def _draw_occluder(
        self, frame: np.ndarray, center: np.ndarray, radius: float, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray]:
        # a sheet of cardboard passing in front of the ball, covering it fully
        size = np.array([rng.uniform(2.6, 4.0), rng.uniform(2.6, 4.0)]) * max(radius, 4.0)
        offset = rng.uniform(-0.3, 0.3, size=2) * max(radius, 4.0)
        low, high = center + offset - size / 2, center + offset + size / 2
        color = _bgr_from_hsv(rng.integers(12, 25), rng.integers(60, 110), rng.integers(110, 170))
        cv2.rectangle(frame, _pt(low), _pt(high), color, -1, cv2.LINE_AA, shift=_SHIFT)
        return low, high

    def _visible_fraction(
        self, t: int, order: np.ndarray, occluders: list[tuple[np.ndarray, np.ndarray]]
    ) -> np.ndarray:
        cam = self.camera
        centers, radii = self._centers[t], self._radii[t]
        grid = np.linspace(-1.0, 1.0, 21)
        gx, gy = np.meshgrid(grid, grid)
        inside = gx**2 + gy**2 <= 1.0
        fractions = np.zeros(2)
        for rank, i in enumerate(order):
            px = centers[i, 0] + radii[i] * gx[inside]
            py = centers[i, 1] + radii[i] * gy[inside]
            seen = (px >= 0) & (px < cam.width) & (py >= 0) & (py < cam.height)
            for j in order[rank + 1 :]:  # nearer balls drawn over this one
                seen &= (px - centers[j, 0]) ** 2 + (py - centers[j, 1]) ** 2 > radii[j] ** 2
            for low, high in occluders:
                seen &= ~((px >= low[0]) & (px <= high[0]) & (py >= low[1]) & (py <= high[1]))
            fractions[i] = seen.mean()
        return fractions

    def _degrade(self, frame: np.ndarray, rng: np.random.Generator, t: int) -> np.ndarray:
        scene = self.scene
        if scene.blur_probability > 0 and rng.random() < scene.blur_probability:
            length = rng.uniform(3.0, max(3.0, scene.blur_px))
            angle = rng.uniform(0, math.pi)
            size = int(math.ceil(length)) | 1
            kernel = np.zeros((size, size), np.float32)
            c = size // 2
            d = 0.5 * (length - 1) * np.array([math.cos(angle), math.sin(angle)])
            cv2.line(
                kernel,
                _pt(np.array([c, c]) - d),
                _pt(np.array([c, c]) + d),
                1.0,
                1,
                cv2.LINE_AA,
                shift=_SHIFT,
            )
            kernel /= kernel.sum()
            frame = cv2.filter2D(frame, -1, kernel, borderType=cv2.BORDER_REFLECT)
        if scene.lighting > 0 or scene.noise_sigma > 0 or scene.flicker > 0:
            out = frame.astype(np.float32)
            if scene.flicker > 0:
                out *= 1.0 + scene.flicker * math.sin(2 * math.pi * t / 3.7 + scene.seed)
            if scene.lighting > 0:
                h, w = frame.shape[:2]
                gain = 1.0 + rng.uniform(-scene.lighting, scene.lighting)
                gx, gy = rng.uniform(-scene.lighting, scene.lighting, size=2)
                ramp = (
                    gain
                    + gx * np.linspace(-1, 1, w, dtype=np.float32)[None, :]
                    + gy * np.linspace(-1, 1, h, dtype=np.float32)[:, None]
                )
                tint = 1.0 + rng.uniform(-0.3, 0.3, size=3).astype(np.float32) * scene.lighting
                out *= ramp[..., None] * tint
            if scene.noise_sigma > 0:
                out += rng.standard_normal(out.shape, dtype=np.float32) * scene.noise_sigma
            frame = np.clip(out, 0, 255).astype(np.uint8)
        return frame


def _draw_ball(
    frame: np.ndarray, center: np.ndarray, radius: float, color: tuple[int, int, int]
) -> None:
    """A shaded, anti-aliased disk; pixel (i, j) is sampled at (i + 0.5, j + 0.5)."""
    h, w = frame.shape[:2]
    x0, x1 = int(math.floor(center[0] - radius - 1)), int(math.ceil(center[0] + radius + 1))
    y0, y1 = int(math.floor(center[1] - radius - 1)), int(math.ceil(center[1] + radius + 1))
    x0c, x1c, y0c, y1c = max(x0, 0), min(x1, w), max(y0, 0), min(y1, h)
    if x0c >= x1c or y0c >= y1c:
        return
    xs = np.arange(x0c, x1c) + 0.5 - center[0]
    ys = np.arange(y0c, y1c) + 0.5 - center[1]
    d = np.sqrt(xs[None, :] ** 2 + ys[:, None] ** 2)
    coverage = np.clip(radius + 0.5 - d, 0.0, 1.0)[..., None]
    # lit from the camera: brightest in the middle, darker towards the rim
    shade = 0.6 + 0.4 * np.sqrt(np.clip(1.0 - (d / radius) ** 2, 0.0, 1.0))[..., None]
    ball = np.asarray(color, np.float64) * shade
    patch = frame[y0c:y1c, x0c:x1c].astype(np.float64)
    frame[y0c:y1c, x0c:x1c] = np.round(patch * (1 - coverage) + ball * coverage).astype(np.uint8)


def _draw_distractor(
    frame: np.ndarray,
    kind: str,
    center: np.ndarray,
    radius: float,
    color: tuple[int, int, int],
    angle: float,
) -> None:
    """A look-alike of a ball: a book (rectangle of the ball's area or more) or a round object."""
    if kind == "round":
        _draw_ball(frame, center, radius, color)
        return
    side = radius * math.sqrt(math.pi)  # a square of the disk's area
    aspect = 0.75
    box = (
        (float(center[0]), float(center[1])),
        (side / math.sqrt(aspect) * 1.2, side * math.sqrt(aspect) * 1.2),
        angle,
    )
    corners = np.round(cv2.boxPoints(box) * _ONE).astype(np.int32)
    cv2.fillPoly(frame, [corners], color, cv2.LINE_AA, shift=_SHIFT)


def oscillating_hands(
    n_steps: int, period: float = 12.0, seed: int = 0, amplitude: float = 0.15, noise: float = 0.0
) -> np.ndarray:
    """A simple test trajectory, shape (n_steps, 2, 3): both hands circle in front of the user.

    The left hand (index 0) at robot-frame y ≈ -0.2 (the robot's right), the right hand at
    y ≈ +0.2, about 0.95 m in front of the robot, circling in opposite phase.
    """
    rng = np.random.default_rng(seed)
    t = np.arange(n_steps) * 2 * math.pi / period
    hands = np.empty((n_steps, 2, 3))
    for i, (y0, sign) in enumerate(((-0.2, 1.0), (0.2, -1.0))):
        hands[:, i, 0] = 0.95 + 0.05 * np.sin(t + i)
        hands[:, i, 1] = y0 + amplitude * np.cos(t) * sign
        hands[:, i, 2] = 0.72 + amplitude * np.sin(t)
    return hands + noise * rng.standard_normal(hands.shape)
