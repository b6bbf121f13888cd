"""Deterministic clips of flat rotors with a known rate: fans, spoked wheels and checkered discs
whose picture repeats ``symmetry`` times a turn, seen face on or tilted, over a still background.

A picture that repeats n times a turn comes back after 1/n of a turn: these clips are the ground
truth for telling a repeat from a turn. Each frame is the rotor's texture turned by the exact
angle ``omega t`` about its centre (and squashed by the cosine of the tilt, an orthographic view
from off the axis), laid over a still textured background; ``mark`` paints one blade differently,
breaking the symmetry as a sticker or a valve on a wheel does.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import asdict, dataclass
from pathlib import Path

import cv2
import numpy as np

from rotrate_cli.errors import InputError, OutputError

ROTOR_KINDS = ("fan", "spokes", "checker")


@dataclass(frozen=True)
class RotorScene:
    """A flat rotor and its camera.

    Attributes:
        kind: ``fan`` (blades with gaps), ``spokes`` (a rim, a hub and thin spokes) or ``checker``
            (a whole disc in alternating sectors).
        symmetry: how many times the picture repeats a turn (blades, spokes, sector pairs).
        omega_rad_s: the rate, rad/s; negative turns clockwise as the picture shows it.
        fps, duration_s: the clip's frame rate and length.
        width_px, height_px: the frame.
        radius_px: the rotor's radius in the picture (its long half-axis when tilted).
        centre_px: where its axis meets the picture; None for the frame's centre. It may lie
            outside the frame (part of the rotor seen).
        tilt_deg: how far the axis leans from the line of sight (0 face on).
        mark: paint one blade apart, so that the picture repeats only once a turn.
        noise: sensor noise, grey levels (standard deviation).
        texture: how much fine texture the rotor carries, 0 (flat paint: only its edges show)
            to 1.
        weather: slow change over the whole picture, as through a window on a rainy day (0: none,
            1: the light across the picture swinging by a third, drops running down the glass,
            the camera drifting 4 pixels over the clip); the picture then never returns exactly.
        roll_deg_s: the camera's own roll, degrees a second (anticlockwise as the picture shows
            it, for a positive rate): the whole picture turned about its centre, enlarged by a
            seventh so that no corner shows; the rotor's rate stays ``omega_rad_s`` against the
            still background.
        seed: of the textures and the noise.
    """

    kind: str = "fan"
    symmetry: int = 5
    omega_rad_s: float = 2.0
    fps: float = 30.0
    duration_s: float = 4.0
    width_px: int = 480
    height_px: int = 360
    radius_px: float = 150.0
    centre_px: tuple[float, float] | None = None
    tilt_deg: float = 0.0
    mark: bool = False
    noise: float = 2.0
    texture: float = 1.0
    weather: float = 0.0
    roll_deg_s: float = 0.0
    seed: int = 0

    @property
    def frame_count(self) -> int:
        return int(round(self.duration_s * self.fps))

    @property
    def centre(self) -> tuple[float, float]:
        if self.centre_px is not None:
            return self.centre_px
        return ((self.width_px - 1) / 2.0, (self.height_px - 1) / 2.0)


def check_rotor(scene: RotorScene) -> None:
    """Raise InputError where the scene cannot be rendered."""
    if scene.kind not in ROTOR_KINDS:
        raise InputError(f"`kind` must be one of {', '.join(ROTOR_KINDS)}; got {scene.kind!r}")
    if not 1 <= scene.symmetry <= 64:
        raise InputError("`symmetry` must be a whole number from 1 to 64")
    if not (scene.fps > 0 and scene.frame_count >= 3):
        raise InputError("the clip needs a positive `fps` and a `duration_s` of at least 3 frames")
    if not 0 <= scene.tilt_deg < 85:
        raise InputError("`tilt_deg` must be between 0 and 85 degrees")


def _texture(size: int, rng: np.random.Generator, scale_px: float) -> np.ndarray:
    """A smooth random texture in 0..255 (blurred noise, stretched to the full range)."""
    noise = rng.standard_normal((size, size)).astype(np.float32)
    blurred = cv2.GaussianBlur(noise, (0, 0), scale_px)
    blurred -= blurred.min()
    return 255.0 * blurred / max(float(blurred.max()), 1e-6)


def _rotor_image(scene: RotorScene, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """The rotor's texture (grey, float) and its coverage (0..1), on a square of twice its
    radius, exactly ``symmetry``-fold symmetric: every sector is the first one turned."""
    size = int(2 * math.ceil(scene.radius_px) + 3)
    c = (size - 1) / 2.0
    y, x = np.mgrid[0:size, 0:size].astype(np.float32)
    dx, dy = x - c, y - c
    r = np.hypot(dx, dy)
    phi = np.mod(np.arctan2(dy, dx), 2 * np.pi)
    sector = 2 * np.pi / scene.symmetry
    k = np.floor(phi / sector)
    back = -k * sector  # each sector read from the first one
    sx = (c + dx * np.cos(back) - dy * np.sin(back)).astype(np.float32)
    sy = (c + dx * np.sin(back) + dy * np.cos(back)).astype(np.float32)
    texture = cv2.remap(_texture(size, rng, 2.5), sx, sy, cv2.INTER_LINEAR)
    texture = scene.texture * texture + (1.0 - scene.texture) * 200.0
    within = phi - k * sector  # the angle inside the sector
    radius = scene.radius_px
    if scene.kind == "fan":
        cover = ((within < 0.55 * sector) & (r <= radius)) | (r <= 0.18 * radius)
    elif scene.kind == "spokes":
        spoke = np.abs(r * np.sin(within)) <= max(2.0, 0.025 * radius)
        cover = ((spoke & (within < 0.5 * sector)) & (r <= radius)) | ((r >= 0.88 * radius) & (r <= radius)) \
            | (r <= 0.15 * radius)
    else:
        cover = r <= radius
        half = (within < 0.5 * sector) ^ (np.floor(r / (0.25 * radius)) % 2 == 1)
        texture = np.where(half, 0.55 * texture + 110.0, 0.55 * texture).astype(np.float32)
    if scene.mark:  # one blade painted apart: the picture repeats once a turn
        first = (k == 0) & (r >= 0.3 * radius)
        texture = np.where(first, 255.0 - texture, texture).astype(np.float32)
    coverage = cv2.GaussianBlur(cover.astype(np.float32), (0, 0), 0.7)
    return texture, coverage


def rotor_frames(scene: RotorScene) -> Iterator[np.ndarray]:
    """The clip's frames, BGR uint8, one at a time."""
    check_rotor(scene)
    rng = np.random.default_rng(scene.seed)
    texture, coverage = _rotor_image(scene, rng)
    background = _texture(max(scene.width_px, scene.height_px), rng, 4.0)[:scene.height_px, :scene.width_px]
    background = 0.6 * background + 40.0
    size = texture.shape[0]
    c = (size - 1) / 2.0
    cx, cy = scene.centre
    squash = math.cos(math.radians(scene.tilt_deg))
    noise_rng = np.random.default_rng(scene.seed + 1)
    weather = _Weather(scene, np.random.default_rng(scene.seed + 2)) if scene.weather > 0 else None
    for index in range(scene.frame_count):
        # the picture turns anticlockwise as shown for a positive rate (image rows point down)
        angle = -scene.omega_rad_s * index / scene.fps
        cos_a, sin_a = math.cos(angle), math.sin(angle)
        # rotor square -> picture: turn about the centre, squash the rows, move to the axis
        matrix = np.array([[cos_a, -sin_a, 0.0], [squash * sin_a, squash * cos_a, 0.0]], np.float64)
        matrix[:, 2] = np.array([cx, cy]) - matrix[:, :2] @ np.array([c, c])
        if weather is not None:
            matrix[:, 2] += weather.drift_px(index)
        shape = (scene.width_px, scene.height_px)
        turned = cv2.warpAffine(texture, matrix, shape, flags=cv2.INTER_LINEAR, borderValue=0.0)
        covered = cv2.warpAffine(coverage, matrix, shape, flags=cv2.INTER_LINEAR, borderValue=0.0)
        grey = covered * turned + (1.0 - covered) * background
        if weather is not None:
            grey = weather.over(grey, index)
        if scene.roll_deg_s:
            centre = ((scene.width_px - 1) / 2.0, (scene.height_px - 1) / 2.0)
            roll = cv2.getRotationMatrix2D(centre, scene.roll_deg_s * index / scene.fps, 1.15)
            grey = cv2.warpAffine(grey, roll, shape, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
        if scene.noise > 0:
            grey = grey + noise_rng.normal(0.0, scene.noise, grey.shape)
        image = np.clip(np.rint(grey), 0, 255).astype(np.uint8)
        yield cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)


class _Weather:
    """Slow change laid over a rotor's frames (:attr:`RotorScene.weather`): light that swings
    across the picture, drops that run down the glass in front of it, a camera that drifts."""

    def __init__(self, scene: RotorScene, rng: np.random.Generator) -> None:
        self.scene = scene
        self.count = scene.frame_count
        h, w = scene.height_px, scene.width_px
        y, x = np.mgrid[0:h, 0:w].astype(np.float32)
        self.across = (x / w - 0.5) + 0.5 * (y / h - 0.5)  # the light's slope across the picture
        drops = int(round(40 * scene.weather))
        self.drops = [(rng.uniform(0, w), rng.uniform(-h, h), rng.uniform(4, 12), rng.uniform(0.3, 1.2),
                       rng.uniform(20, 60)) for _ in range(drops)]  # x, first y, size, speed px/frame, brightness
        self.canvas = np.zeros((h, w), np.float32)

    def drift_px(self, index: int) -> np.ndarray:
        share = index / max(self.count - 1, 1)
        return 4.0 * self.scene.weather * np.array([share, 0.5 * math.sin(math.pi * share)])

    def over(self, grey: np.ndarray, index: int) -> np.ndarray:
        share = index / max(self.count - 1, 1)
        strength = self.scene.weather
        gain = 1.0 + strength * 0.06 * math.sin(2.0 * math.pi * 0.7 * share)
        tilt = strength * 0.35 * math.sin(2.0 * math.pi * 0.45 * share + 0.5)
        lit = grey * (gain + tilt * self.across)
        canvas = self.canvas
        canvas[:] = 0.0
        h = self.scene.height_px
        for x, y0, size, speed, bright in self.drops:
            y = (y0 + speed * index) % (2 * h) - 0.5 * h
            cv2.ellipse(canvas, (int(x), int(y)), (int(size * 0.6), int(size)), 0, 0, 360, float(bright), -1)
        return lit + cv2.GaussianBlur(canvas, (0, 0), 3.0)


def rotor_truth(scene: RotorScene) -> dict[str, object]:
    """What the clip shows: the rate, its sense, where the axis meets the picture, the repeats."""
    record: dict[str, object] = asdict(scene)
    record.update(omega_rad_s=abs(scene.omega_rad_s), fixation_px=list(scene.centre),
                  direction="ccw" if scene.omega_rad_s > 0 else "cw",
                  repeats_per_turn=1 if scene.mark else scene.symmetry, frame_count=scene.frame_count)
    return record


def write_rotor_clip(scene: RotorScene, path: str | Path, force: bool = False) -> dict[str, object]:
    """Render ``scene`` to an MPEG-4 video at ``path``; returns its truth (see :func:`rotor_truth`).

    Raises:
        InputError: a scene that cannot be rendered.
        OutputError: ``path`` exists and ``force`` is False, or it cannot be written.
    """
    path = Path(path)
    check_rotor(scene)
    if path.exists() and not force:
        raise OutputError(f"{path} exists; pass `force` to replace it")
    partial = path.with_name(f".{path.stem}.partial{path.suffix}")
    writer = cv2.VideoWriter(str(partial), cv2.VideoWriter_fourcc(*"mp4v"), scene.fps,
                             (scene.width_px, scene.height_px))
    if not writer.isOpened():
        raise OutputError(f"could not open a video writer for {path}")
    try:
        for frame in rotor_frames(scene):
            writer.write(frame)
    except BaseException:
        writer.release()
        partial.unlink(missing_ok=True)
        raise
    writer.release()
    partial.replace(path)
    return rotor_truth(scene)
