"""Pictures of a measurement: a still with a pixel grid and the axis (``rotrate frame``), and a
video with the axis, the tracks and the running omega drawn on every frame (``--overlay``).

Drawing only: the measurements come from :mod:`rotrate_cli.analysis`; files are written through
a temporary name and a rename, so an interrupted run leaves nothing half-written.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import cv2
import numpy as np

from rotrate_cli.errors import InputError, OutputError
from rotrate_cli.output.files import replacing
from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.scene.axis import unit_offset
from rotrate_cli.video.decode import FrameSource
from rotrate_cli.video.frames import Frame

if TYPE_CHECKING:
    from rotrate_cli.tracking.steady import CameraPath

#: Colours (BGR).
AXIS_COLOUR = (0, 215, 255)
INLIER_COLOUR = (80, 220, 80)
REJECTED_COLOUR = (60, 60, 235)
#: Rejected tracks named by where they are (see :mod:`rotrate_cli.scene.reasons`), in their own colours.
NAMED_COLOURS = {"reflection": (255, 255, 0), "slides": (0, 165, 255), "other_motion": (255, 0, 255)}
GRID_COLOUR = (255, 255, 255)
TEXT_COLOUR = (255, 255, 255)
#: Seconds of each track's path drawn behind its point.
TRAIL_S = 0.5


def frame_at(source: FrameSource, time_s: float) -> Frame:
    """The first frame at or after ``time_s`` (BGR).

    Raises:
        InputError: the clip ends before ``time_s``.
    """
    if not (math.isfinite(time_s) and time_s >= 0):
        raise InputError("`at_s` takes a time in seconds, 0 or later")
    source.use_ffmpeg(only_if_interlaced=True)
    for frame in source.frames(start_s=time_s):
        # OpenCV decodes an interlaced stream black or garbled in some openings and not others,
        # and not always from the first frame (the frame command's still of the interlaced test
        # file was mostly black in 2 of about 10 runs of the suite): read that frame through
        # FFmpeg where it can be
        if source.looks_undecoded(frame.image) and source.use_ffmpeg():
            return frame_at(source, time_s)
        return frame
    raise InputError(f"{source.info.source} ends before {time_s:g} s")


def draw_grid(image: np.ndarray, step_px: int = 50) -> np.ndarray:
    """A copy of ``image`` with a faint pixel grid every ``step_px`` and rulers labelled every
    other line along the top and left edges (x and y in pixels)."""
    out = image.copy()
    height, width = out.shape[:2]
    grid = out.copy()
    for x in range(0, width, step_px):
        cv2.line(grid, (x, 0), (x, height - 1), GRID_COLOUR, 1)
    for y in range(0, height, step_px):
        cv2.line(grid, (0, y), (width - 1, y), GRID_COLOUR, 1)
    out = cv2.addWeighted(grid, 0.25, out, 0.75, 0)
    scale = max(0.35, min(width, height) / 900)
    for x in range(0, width, 2 * step_px):
        cv2.line(out, (x, 0), (x, 8), GRID_COLOUR, 1)
        _label(out, str(x), (x + 2, int(18 * scale / 0.35 * 0.7) + 4), scale)
    for y in range(2 * step_px, height, 2 * step_px):
        _label(out, str(y), (3, y - 4), scale)  # just above its grid line
    return out


def draw_axis(image: np.ndarray, point_px: tuple[float, float], angle_deg: float, label: str = "") -> None:
    """Draw the axis through ``point_px`` at ``angle_deg`` (0 vertical) across the whole image,
    a cross at the point, and ``label`` beside it (in place); nothing where no axis was found (a
    rate from the picture's return alone: its point is NaN)."""
    if not all(math.isfinite(value) for value in (*point_px, angle_deg)):
        return
    ux, uy = unit_offset(angle_deg)
    along = (-uy, ux)  # the axis runs perpendicular to the offset direction
    reach = 2.0 * (image.shape[0] + image.shape[1])
    x, y = point_px
    start = (int(round(x - along[0] * reach)), int(round(y - along[1] * reach)))
    end = (int(round(x + along[0] * reach)), int(round(y + along[1] * reach)))
    cv2.line(image, start, end, AXIS_COLOUR, 1, cv2.LINE_AA)
    centre = (int(round(x)), int(round(y)))
    cv2.drawMarker(image, centre, AXIS_COLOUR, cv2.MARKER_CROSS, 17, 2)
    if label:
        _label(image, label, (centre[0] + 10, centre[1] - 10), max(0.4, min(image.shape[:2]) / 900))


def _label(image: np.ndarray, text: str, origin: tuple[int, int], scale: float) -> None:
    """Text with a dark outline, readable on any background. The outline is the text itself, one
    pixel thick, drawn one pixel off all round: OpenCV 5 spaces a thicker line's letters wider
    (a 3-pixel "rejected" ran 4 px longer than a 1-pixel one), so an outline drawn thick read as
    doubled letters ("rejectedd")."""
    x, y = origin
    for dx, dy in ((-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)):
        cv2.putText(image, text, (x + dx, y + dy), cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 0, 0), 1, cv2.LINE_AA)
    cv2.putText(image, text, origin, cv2.FONT_HERSHEY_SIMPLEX, scale, TEXT_COLOUR, 1, cv2.LINE_AA)


def write_image(path: Path, image: np.ndarray, force: bool) -> None:
    """Write a PNG (or any format OpenCV knows from the suffix) through a temporary name."""
    with replacing(path, force, suffix=path.suffix or ".png") as temporary:
        if not cv2.imwrite(str(temporary), image):
            raise OutputError(f"could not write {path}; use a .png or .jpg name")


def write_overlay(
    source: FrameSource,
    path: Path,
    tracks: pd.DataFrame,
    inliers: set[int],
    point_px: tuple[float, float],
    angle_deg: float,
    running: Callable[[float], tuple[float, float, float]],
    start_s: float = 0.0,
    end_s: float | None = None,
    force: bool = False,
    named: dict[int, str] | None = None,
    progress: Callable[[int, int | None], None] | None = None,
    camera: CameraPath | None = None,
    tag: str = "",
) -> int:
    """Write the overlay video: each frame of ``source`` between ``start_s`` and ``end_s`` with
    the axis, each track's last :data:`TRAIL_S` of path (inliers green, rejected red, those
    ``named`` reflection, slides or other_motion in :data:`NAMED_COLOURS`, with a legend), and
    the running omega ``running(time_s) -> (omega, low, high)`` written on it.

    ``tracks`` has ``track, frame, x_px, y_px`` (features numbered as in the report).
    ``progress`` is called after each frame written with the count so far and the source's frame
    count (None where unknown). ``camera``: a moving camera's path, where the axis (``point_px``,
    ``angle_deg``, where the camera stood at the first frame) is drawn where it saw it. ``tag``: a
    word written after the rate (``weak``). Returns the number of frames written.
    """
    info = source.info
    fourcc = cv2.VideoWriter_fourcc(*("mp4v" if path.suffix.lower() in {".mp4", ".mov", ".mkv", ""} else "MJPG"))
    with replacing(path, force, suffix=path.suffix or ".mp4") as temporary:
        writer = cv2.VideoWriter(str(temporary), fourcc, info.fps, (info.width_px, info.height_px))
        if not writer.isOpened():
            raise OutputError(f"could not open a video writer for {path}; use a .mp4 or .avi name")
        try:
            return _draw_frames(source, writer, tracks, inliers, point_px, angle_deg, running, start_s, end_s,
                                named or {}, progress, camera, tag)
        finally:
            writer.release()


def _draw_frames(
    source: FrameSource, writer: cv2.VideoWriter, tracks: pd.DataFrame, inliers: set[int],
    point_px: tuple[float, float], angle_deg: float, running: Callable[[float], tuple[float, float, float]],
    start_s: float, end_s: float | None, named: dict[int, str],
    progress: Callable[[int, int | None], None] | None = None, camera: CameraPath | None = None, tag: str = "",
) -> int:
    """Draw and write the overlay's frames (see :func:`write_overlay`); returns how many."""
    info = source.info
    by_frame = {int(frame): part for frame, part in tracks.groupby("frame", sort=False)}
    history: dict[int, list[tuple[float, int, int]]] = {}
    written = 0
    scale = max(0.45, min(info.width_px, info.height_px) / 800)
    for frame in source.frames(start_s, end_s):
        image = frame.image
        draw_axis(image, *_axis_seen(point_px, angle_deg, camera, frame.index))
        here = by_frame.get(frame.index)
        if here is not None:
            for track, x, y in zip(here["track"].to_numpy(), here["x_px"].to_numpy(), here["y_px"].to_numpy(),
                                   strict=True):
                history.setdefault(int(track), []).append((frame.time_s, int(round(x)), int(round(y))))
        for track, trail in list(history.items()):
            while trail and frame.time_s - trail[0][0] > TRAIL_S:
                trail.pop(0)
            if not trail:
                del history[track]
                continue
            if trail[-1][0] < frame.time_s - 1e-9:
                continue  # the track has ended: its trail is no longer drawn
            colour = (INLIER_COLOUR if track in inliers
                      else NAMED_COLOURS.get(named.get(track, ""), REJECTED_COLOUR))
            points = np.array([(x, y) for _, x, y in trail], np.int32)
            if len(points) > 1:
                cv2.polylines(image, [points], False, colour, 1, cv2.LINE_AA)
            cv2.circle(image, (int(points[-1][0]), int(points[-1][1])), 2, colour, -1, cv2.LINE_AA)
        omega, low, high = running(frame.time_s)
        text = (f"omega {omega:.4f} rad/s [{low:.4f}, {high:.4f}]{'  ' + tag if tag else ''}  t {frame.time_s:.2f} s"
                if math.isfinite(omega) else f"omega: not yet  t {frame.time_s:.2f} s")
        # on a dark band: the codec then keeps the changing text sharp
        cv2.rectangle(image, (0, 0), (image.shape[1] - 1, int(42 * scale)), (0, 0, 0), -1)
        _label(image, text, (10, int(30 * scale)), scale)
        _legend(image, scale, sorted(set(named.values()) & set(NAMED_COLOURS)))
        writer.write(image)
        written += 1
        if progress is not None:
            progress(written, info.frame_count)
    return written


def _axis_seen(point_px: tuple[float, float], angle_deg: float, camera: CameraPath | None,
               frame: int) -> tuple[tuple[float, float], float]:
    """The axis's point and angle where a moving ``camera`` saw them at ``frame`` (as given
    without one)."""
    if camera is None:
        return point_px, angle_deg
    ux, uy = unit_offset(angle_deg)
    x, y = camera.redo(np.full(2, frame), np.array([point_px[0], point_px[0] + ux]),
                       np.array([point_px[1], point_px[1] + uy]))
    return (float(x[0]), float(y[0])), math.degrees(math.atan2(float(y[1] - y[0]), float(x[1] - x[0])))


def _legend(image: np.ndarray, scale: float, names: list[str]) -> None:
    height = image.shape[0]
    y = height - int(12 * scale / 0.45)
    entries = [(INLIER_COLOUR, "used"), *((NAMED_COLOURS[name], name.replace("_", " ")) for name in names),
               (REJECTED_COLOUR, "rejected"), (AXIS_COLOUR, "axis")]
    for colour, text in entries:
        cv2.circle(image, (14, y - 4), 5, colour, -1)
        _label(image, text, (24, y), scale)
        y -= int(22 * scale / 0.45)
