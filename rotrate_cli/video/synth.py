"""Deterministic synthetic clips with a known rotation rate: the ground truth for our tests.

A textured solid (box, cylinder or sphere) spins about a vertical axis (optionally speeding up,
optionally beside a second solid with its own axis and rate, optionally seen by a rolled camera
so that the axis is tilted in the image) in front of a static textured background and is
ray-cast per pixel (supersampled, then area-averaged), under
orthographic or pinhole projection. The object's texture is a solid 3D noise fixed to the
object, so every surface point carries the same pattern as it turns; a fixed light shades it.

World frame: X right, Y up, Z towards the camera; the axis is the line X = X0, Z = 0. A positive
``omega_rad_s`` turns the object anticlockwise seen from above (its near side moves right).
"""

from __future__ import annotations

import json
import math
from collections import deque
from collections.abc import Iterable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path

import cv2
import numpy as np
from scipy import ndimage

from rotrate_cli.errors import InputError, OutputError
from rotrate_cli.runtime.choices import PROJECTIONS, SHAPES  # noqa: F401 - re-exported
from rotrate_cli.runtime.pools import available_cores

_BOX_HALF = np.array([0.85, 0.95, 0.6])
_CYLINDER = (0.8, 0.95)  # radius, half-height
_SPHERE_RADIUS = 1.0
_TEXTURE_EXTENT = 1.25  # the solid texture covers [-extent, extent]^3 in object units
_LIGHT = np.array([-0.45, 0.55, 1.0]) / np.linalg.norm([-0.45, 0.55, 1.0])
#: The cylinder about its axis that each shape sweeps as it turns (radius, half-height), object units.
_SWEPT = {"box": (math.hypot(_BOX_HALF[0], _BOX_HALF[2]), _BOX_HALF[1]), "cylinder": _CYLINDER,
          "sphere": (_SPHERE_RADIUS, _SPHERE_RADIUS)}


@dataclass(frozen=True)
class SceneConfig:
    """What to render.

    Attributes:
        shape: ``box``, ``cylinder`` or ``sphere``.
        omega_rad_s: signed rate; positive is anticlockwise seen from above.
        fps: frames per second; duration_s: clip length in seconds.
        width_px, height_px: frame size.
        projection: ``orthographic`` or ``perspective``.
        fov_deg: horizontal field of view of the pinhole camera (perspective only).
        object_height_fraction: the object's height as a fraction of the frame height.
        axis_offset_px: horizontal offset of the axis from the frame centre, pixels.
        start_angle_rad: the object's turn at t = 0.
        noise_sigma: standard deviation of added sensor noise, grey levels.
        jpeg_quality: when set (1-100), each frame goes through JPEG at that quality before it
            is written, on top of the video codec: heavy compression, blocks and ringing.
        alpha_rad_s2: angular acceleration; the rate at time t is ``omega_rad_s + alpha_rad_s2 * t``.
        roll_deg: camera roll: the axis's top end leans this many degrees to the right of
            vertical in the image (90: a horizontal axis with its top end to the right).
        elevation_deg: camera elevation: the camera looks down on the object from this many
            degrees above its mid-height plane (the top shows; the axis stays upright in the
            image, tipped towards the camera).
        second_shape: a second solid beside the first (None: none), with its own rate
            ``second_omega_rad_s`` and axis ``second_axis_offset_px`` from the frame centre.
        seed: seeds the textures and the noise: same seed, same clip.
        supersample: rays per pixel along each side (antialiasing).
        symmetry: the surface's texture repeats this many times a turn (bolts on a hub, a
            patterned drum): the picture of a cylinder or sphere then comes back every
            1/symmetry of a turn.
        checker: the surface painted in a checker of 2 x ``symmetry`` columns round the axis and
            bands up it, over its texture.
    """

    shape: str = "box"
    omega_rad_s: float = 0.5
    fps: float = 30.0
    duration_s: float = 5.0
    width_px: int = 640
    height_px: int = 360
    projection: str = "orthographic"
    fov_deg: float = 25.0
    object_height_fraction: float = 0.7
    axis_offset_px: float = 0.0
    start_angle_rad: float = 0.3
    noise_sigma: float = 0.0
    jpeg_quality: int | None = None
    alpha_rad_s2: float = 0.0
    roll_deg: float = 0.0
    elevation_deg: float = 0.0
    second_shape: str | None = None
    second_omega_rad_s: float = 1.0
    second_axis_offset_px: float = 0.0
    seed: int = 0
    supersample: int = 2
    symmetry: int = 1
    checker: bool = False

    @property
    def frame_count(self) -> int:
        """Frames in the clip."""
        return int(round(self.duration_s * self.fps))


def _check(scene: SceneConfig) -> None:
    for shape in (scene.shape, scene.second_shape or scene.shape):
        if shape not in SHAPES:
            raise InputError(f"unknown shape {shape!r}; use one of {', '.join(SHAPES)}")
    if scene.projection not in PROJECTIONS:
        raise InputError(f"unknown projection {scene.projection!r}; use one of {', '.join(PROJECTIONS)}")
    if not (scene.fps > 0 and scene.duration_s > 0 and scene.frame_count >= 3):
        raise InputError("the clip needs a positive `fps` and a `duration_s` of at least 3 frames")
    if scene.width_px < 16 or scene.height_px < 16:
        raise InputError("the frame must be at least 16x16 pixels")
    if scene.jpeg_quality is not None and not 1 <= scene.jpeg_quality <= 100:
        raise InputError("`jpeg_quality` must be between 1 and 100")
    if not 0 < scene.fov_deg < 170:
        raise InputError("`fov_deg` must be between 0 and 170 degrees")
    if not -80 <= scene.elevation_deg <= 80:
        raise InputError("`elevation_deg` must be between -80 and 80 degrees")


@dataclass(frozen=True)
class _Body:
    """One spinning solid: its shape, rate, acceleration, axis (object units from the centre),
    solid texture and colour."""

    shape: str
    omega_rad_s: float
    alpha_rad_s2: float
    axis_x: float
    texture: np.ndarray
    tint: np.ndarray


class Renderer:
    """Renders the frames of one scene; frame ``k`` shows time ``k / fps``."""

    def __init__(self, scene: SceneConfig) -> None:
        _check(scene)
        self.scene = scene
        rng = np.random.default_rng(scene.seed)
        ss = scene.supersample
        height, width = scene.height_px, scene.width_px
        self._centre = (width / 2.0 - 0.5, height / 2.0 - 0.5)
        # pixels per object unit at the axis
        half_height = {"box": _BOX_HALF[1], "cylinder": _CYLINDER[1], "sphere": _SPHERE_RADIUS}[scene.shape]
        self._scale = scene.object_height_fraction * height / (2.0 * half_height)
        self._focal_px = (width / 2.0) / math.tan(math.radians(scene.fov_deg) / 2.0)
        self._distance = self._focal_px / self._scale  # camera distance that gives that scale at the axis
        u = (np.arange(width * ss) + 0.5) / ss - 0.5
        v = (np.arange(height * ss) + 0.5) / ss - 0.5
        uu, vv = np.meshgrid(u, v)
        self._shape_ss = uu.shape
        n = uu.size
        # image (right, up) to world (X, Y): the camera is rolled so that world up leans roll_deg right
        roll = math.radians(scene.roll_deg)
        right, up = uu.ravel() - self._centre[0], self._centre[1] - vv.ravel()
        world_x = math.cos(roll) * right - math.sin(roll) * up
        world_y = math.sin(roll) * right + math.cos(roll) * up
        if scene.projection == "orthographic":
            origin = np.column_stack([world_x / self._scale, world_y / self._scale, np.full(n, 10.0)])
            direction = np.tile([0.0, 0.0, -1.0], (n, 1))
        else:
            direction = np.column_stack([world_x / self._focal_px, world_y / self._focal_px, -np.ones(n)])
            direction /= np.linalg.norm(direction, axis=1, keepdims=True)
            origin = np.tile([0.0, 0.0, self._distance], (n, 1))
        # elevation: turn the camera about the world's horizontal image axis, so that it looks
        # down at the object's centre from above its mid-height plane
        tilt = math.radians(scene.elevation_deg)
        to_world = np.array([[1.0, 0.0, 0.0],
                             [0.0, math.cos(tilt), -math.sin(tilt)],
                             [0.0, math.sin(tilt), math.cos(tilt)]])
        self._origin, self._direction = origin @ to_world, direction @ to_world
        tints = {"box": (0.55, 0.75, 1.0), "cylinder": (0.5, 1.0, 0.7), "sphere": (1.0, 0.8, 0.55)}
        self._bodies = [_Body(scene.shape, scene.omega_rad_s, scene.alpha_rad_s2, scene.axis_offset_px / self._scale,
                              self._solid_texture(rng), np.array(tints[scene.shape]))]
        self._rays: list[np.ndarray] = []
        self._background = self._background_image(rng)
        self._noise_seed = int(rng.integers(0, 2**31))
        if scene.second_shape is not None:
            self._bodies.append(_Body(scene.second_shape, scene.second_omega_rad_s, 0.0,
                                      scene.second_axis_offset_px / self._scale, self._solid_texture(rng),
                                      np.array(tints[scene.second_shape])[::-1]))
        # the rays that can meet each body at all, those through the cylinder it sweeps as it
        # turns (the same in every frame, and a little widened): most of a frame is background,
        # and the rays that miss it are left out of the intersections (the same pixels)
        for body in self._bodies:
            radius, half = _SWEPT[body.shape]
            centred = self._origin - np.array([body.axis_x, 0.0, 0.0])
            meets, _ = self._intersect("cylinder", centred, self._direction, (1.01 * radius, 1.01 * half))
            self._rays.append(np.flatnonzero(np.isfinite(meets)))

    def axis_px(self, axis_offset_px: float) -> tuple[float, float]:
        """The pixel where the axis at ``axis_offset_px`` (at the object's mid-height) appears."""
        roll = math.radians(self.scene.roll_deg)
        return (self._centre[0] + math.cos(roll) * axis_offset_px, self._centre[1] + math.sin(roll) * axis_offset_px)

    @property
    def fixation_px(self) -> tuple[float, float]:
        """The pixel where the (first) axis point at the object's mid-height appears."""
        return self.axis_px(self.scene.axis_offset_px)

    @staticmethod
    def _solid_texture(rng: np.random.Generator) -> np.ndarray:
        grid = rng.random((64, 64, 64))
        grid = ndimage.gaussian_filter(grid, 0.8)
        grid = (grid - grid.mean()) / grid.std()
        return np.clip(0.5 + 0.22 * grid, 0.0, 1.0)

    def _background_image(self, rng: np.random.Generator) -> np.ndarray:
        ss = self.scene.supersample
        shape = self._shape_ss
        coarse = rng.random((shape[0] // (6 * ss) + 2, shape[1] // (6 * ss) + 2))
        smooth = cv2.resize(coarse.astype(np.float32), (shape[1], shape[0]), interpolation=cv2.INTER_CUBIC)
        smooth = cv2.GaussianBlur(smooth, (0, 0), 1.5 * ss)
        smooth = (smooth - smooth.mean()) / (smooth.std() + 1e-9)
        grey = np.clip(0.42 + 0.12 * smooth, 0.0, 1.0)
        return np.stack([grey * 0.95, grey * 0.9, grey * 0.8], axis=-1)

    @staticmethod
    def _intersect(shape: str, origin: np.ndarray, direction: np.ndarray,
                   cylinder: tuple[float, float] = _CYLINDER) -> tuple[np.ndarray, np.ndarray]:
        """Distance to the first hit (inf where none) and the surface normal, in object coordinates
        (``cylinder``: the radius and half-height of a cylinder)."""
        n = len(origin)
        normal = np.zeros((n, 3))
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            if shape == "sphere":
                b = np.einsum("ij,ij->i", origin, direction)
                c = np.einsum("ij,ij->i", origin, origin) - _SPHERE_RADIUS**2
                disc = b * b - c
                t = np.where(disc >= 0, -b - np.sqrt(np.maximum(disc, 0)), np.inf)
                hit = origin + t[:, None] * direction
                normal = hit / _SPHERE_RADIUS
            elif shape == "cylinder":
                radius, half = cylinder
                a = direction[:, 0] ** 2 + direction[:, 2] ** 2
                b = origin[:, 0] * direction[:, 0] + origin[:, 2] * direction[:, 2]
                c = origin[:, 0] ** 2 + origin[:, 2] ** 2 - radius**2
                disc = b * b - a * c
                t_side = np.where((disc >= 0) & (a > 1e-12), (-b - np.sqrt(np.maximum(disc, 0))) / a, np.inf)
                y_side = origin[:, 1] + t_side * direction[:, 1]
                t_side = np.where(np.abs(y_side) <= half, t_side, np.inf)
                t_cap = np.full(n, np.inf)
                cap_sign = np.zeros(n)
                for sign in (1.0, -1.0):
                    tc = (sign * half - origin[:, 1]) / direction[:, 1]
                    px = origin[:, 0] + tc * direction[:, 0]
                    pz = origin[:, 2] + tc * direction[:, 2]
                    ok = (tc > 0) & (px**2 + pz**2 <= radius**2) & (tc < t_cap)
                    t_cap = np.where(ok, tc, t_cap)
                    cap_sign = np.where(ok, sign, cap_sign)
                use_cap = t_cap < t_side
                t = np.where(use_cap, t_cap, t_side)
                hit = origin + np.where(np.isfinite(t), t, 0)[:, None] * direction
                normal = np.column_stack([hit[:, 0] / radius, np.zeros(n), hit[:, 2] / radius])
                normal[use_cap] = np.column_stack([np.zeros(use_cap.sum()), cap_sign[use_cap], np.zeros(use_cap.sum())])
            else:
                low = (-_BOX_HALF - origin) / direction
                high = (_BOX_HALF - origin) / direction
                near = np.minimum(low, high)
                far = np.maximum(low, high)
                near = np.nan_to_num(near, nan=-np.inf)
                far = np.nan_to_num(far, nan=np.inf)
                t_near = near.max(axis=1)
                t_far = far.min(axis=1)
                t = np.where((t_near <= t_far) & (t_far > 0), t_near, np.inf)
                axis = near.argmax(axis=1)
                normal[np.arange(n), axis] = -np.sign(direction[np.arange(n), axis])
        return t, normal

    def frames(self, indices: Iterable[int], workers: int | None = None) -> Iterator[np.ndarray]:
        """The BGR frames ``indices``, in order, rendered a few ahead on ``workers`` threads (the
        cores by default): NumPy and SciPy let go of the interpreter in their array work, and
        each frame is rendered on its own, so the frames are those :meth:`render` gives."""
        workers = workers if workers is not None else min(4, available_cores())
        if workers == 1:
            yield from (self.render(index) for index in indices)
            return
        with ThreadPoolExecutor(workers, thread_name_prefix="rotrate-render") as pool:
            pending: deque[Future[np.ndarray]] = deque()
            for index in indices:
                pending.append(pool.submit(self.render, index))
                if len(pending) > 2 * workers:  # a few ahead, not the whole clip in memory
                    yield pending.popleft().result()
            while pending:
                yield pending.popleft().result()

    def render(self, index: int) -> np.ndarray:
        """The BGR uint8 frame ``index``."""
        scene = self.scene
        time_s = index / scene.fps
        image = self._background.reshape(-1, 3).copy()
        nearest = np.full(len(self._origin), np.inf)
        for body, rays in zip(self._bodies, self._rays, strict=True):
            angle = scene.start_angle_rad + body.omega_rad_s * time_s + 0.5 * body.alpha_rad_s2 * time_s**2
            cos_a, sin_a = math.cos(angle), math.sin(angle)
            # object-from-world rotation R_y(-angle), applied to row vectors
            to_object = np.array([[cos_a, 0.0, sin_a], [0.0, 1.0, 0.0], [-sin_a, 0.0, cos_a]])
            shifted = self._origin[rays] - np.array([body.axis_x, 0.0, 0.0])  # object frame centred on its axis
            origin = shifted @ to_object
            direction = self._direction[rays] @ to_object
            t, normal = self._intersect(body.shape, origin, direction)
            hit = np.isfinite(t) & (t < nearest[rays])
            if not hit.any():
                continue
            nearest[rays[hit]] = t[hit]
            points = origin[hit] + t[hit, None] * direction[hit]
            if scene.symmetry > 1 or scene.checker:
                points, sector = _folded(points, scene.symmetry)
            coords = (points + _TEXTURE_EXTENT) / (2 * _TEXTURE_EXTENT) * (body.texture.shape[0] - 1)
            albedo = ndimage.map_coordinates(body.texture, coords.T, order=1, mode="nearest")
            if scene.checker:
                band = np.floor(points[:, 1] / 0.25).astype(int)
                albedo = np.where((sector + band) % 2 == 0, 0.35 + 0.5 * albedo, 0.5 * albedo)
            world_normal = normal[hit] @ to_object.T
            shade = 0.6 + 0.4 * np.clip(world_normal @ _LIGHT, 0.0, 1.0)
            image[rays[hit]] = (albedo * shade)[:, None] * body.tint[None, :]
        image = image.reshape(*self._shape_ss, 3)
        ss = scene.supersample
        small = cv2.resize(image.astype(np.float32), (scene.width_px, scene.height_px),
                           interpolation=cv2.INTER_AREA) if ss > 1 else image.astype(np.float32)
        small = small * 255.0
        if scene.noise_sigma > 0:
            noise_rng = np.random.default_rng((self._noise_seed, index))
            small = small + noise_rng.normal(0.0, scene.noise_sigma, small.shape)
        frame = np.clip(np.rint(small), 0, 255).astype(np.uint8)[:, :, ::-1].copy()
        if scene.jpeg_quality is not None:
            _, encoded = cv2.imencode(".jpg", frame, [cv2.IMWRITE_JPEG_QUALITY, int(scene.jpeg_quality)])
            frame = cv2.imdecode(encoded, cv2.IMREAD_COLOR)
        return frame


def truth(scene: SceneConfig, renderer: Renderer) -> dict[str, object]:
    """The ground truth of a rendered clip, as written next to it."""
    record: dict[str, object] = {
        "omega_rad_s": abs(scene.omega_rad_s),
        "direction": "ccw" if scene.omega_rad_s > 0 else "cw",
        "fixation_px": [round(v, 3) for v in renderer.fixation_px],
        "axis_angle_deg": scene.roll_deg,
        "frames": scene.frame_count,
        "renderer": "rotrate synth",
        "scene": asdict(scene),
    }
    if scene.alpha_rad_s2:
        record["alpha_rad_s2"] = scene.alpha_rad_s2 if scene.omega_rad_s >= 0 else -scene.alpha_rad_s2
    if scene.second_shape is not None:
        record["bodies"] = [
            {"omega_rad_s": abs(omega), "direction": "ccw" if omega > 0 else "cw",
             "axis_px": [round(v, 3) for v in renderer.axis_px(offset)]}
            for omega, offset in ((scene.omega_rad_s, scene.axis_offset_px),
                                  (scene.second_omega_rad_s, scene.second_axis_offset_px))
        ]
    return record


def write_clip(scene: SceneConfig, path: str | Path, force: bool = False) -> dict[str, object]:
    """Render ``scene`` to an MPEG-4 video at ``path`` and its truth to ``path`` with ``.json``.

    Writes to temporary names and renames, so an interrupted render leaves nothing behind.
    Returns the truth dictionary.

    Raises:
        OutputError: a target exists and ``force`` is False, or it cannot be written.
    """
    path = Path(path)
    truth_path = path.with_suffix(".json")
    for target in (path, truth_path):
        if target.exists() and not force:
            raise OutputError(f"{target} exists; pass `force` to replace it")
    if not path.parent.is_dir():
        raise OutputError(f"the folder {path.parent} does not exist")
    renderer = Renderer(scene)
    partial = path.with_name(f".{path.stem}.partial{path.suffix}")
    fourcc = cv2.VideoWriter_fourcc(*("mp4v" if path.suffix.lower() in {".mp4", ".mov", ".mkv"} else "MJPG"))
    writer = cv2.VideoWriter(str(partial), fourcc, scene.fps, (scene.width_px, scene.height_px))
    if not writer.isOpened():
        raise OutputError(f"could not open a video writer for {path}")
    try:
        for frame in renderer.frames(range(scene.frame_count)):
            writer.write(frame)
    except BaseException:
        writer.release()
        partial.unlink(missing_ok=True)
        raise
    writer.release()
    record = truth(scene, renderer)
    partial_truth = truth_path.with_name(f".{truth_path.name}.partial")
    partial_truth.write_text(json.dumps(record, indent=2) + "\n")
    partial.replace(path)
    partial_truth.replace(truth_path)
    return record


def _folded(points: np.ndarray, symmetry: int) -> tuple[np.ndarray, np.ndarray]:
    """Object points turned back about the axis (y) into the first of ``symmetry`` sectors, and
    which half-sector each lay in (for a checker of 2 x ``symmetry`` columns)."""
    sector = 2.0 * math.pi / max(symmetry, 1)
    azimuth = np.mod(np.arctan2(points[:, 2], points[:, 0]), 2.0 * math.pi)
    k = np.floor(azimuth / sector)
    back = -k * sector
    cos_b, sin_b = np.cos(back), np.sin(back)
    folded = points.copy()
    folded[:, 0] = points[:, 0] * cos_b - points[:, 2] * sin_b
    folded[:, 2] = points[:, 0] * sin_b + points[:, 2] * cos_b
    half = np.floor(np.mod(azimuth, sector) / (0.5 * sector)).astype(int)
    return folded, half
