"""Image sequences: a printf pattern (``frames/viff.%03d.png``) or a folder of images in natural
name order, their clock (given times, the photographs' EXIF capture times, or a given rate) and
their frames."""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from rotrate_cli.errors import InputError
from rotrate_cli.video.frames import Frame, VideoInfo, mean_rate

IMAGE_SUFFIXES = frozenset({".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp", ".pgm", ".ppm"})


def image_files(source: str) -> list[Path]:
    """The images of a printf pattern or a folder, in order.

    Raises:
        InputError: a bad pattern, or no image.
    """
    return _pattern_files(source) if "%" in Path(source).name else _folder_files(Path(source))


def _natural_key(name: str) -> list[Any]:
    return [int(part) if part.isdigit() else part.lower() for part in re.split(r"(\d+)", name)]


def _pattern_files(pattern: str) -> list[Path]:
    """Expand a printf pattern such as ``dir/img.%03d.png`` to the existing files, in order.

    Numbering starts at the first existing index among 0..9999 and stops at the first gap,
    as OpenCV's image-sequence reader does.
    """
    try:
        pattern % 0
    except (TypeError, ValueError) as exc:
        raise InputError(f"bad image pattern {pattern!r}: use one printf field such as %03d") from exc
    first = next((i for i in range(10_000) if Path(pattern % i).is_file()), None)
    if first is None:
        raise InputError(f"no image matches the pattern {pattern!r}; check the folder and the %d field")
    files = []
    index = first
    while Path(pattern % index).is_file():
        files.append(Path(pattern % index))
        index += 1
    return files


def _folder_files(folder: Path) -> list[Path]:
    files = [p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES]
    if not files:
        raise InputError(f"the folder {folder} holds no images ({', '.join(sorted(IMAGE_SUFFIXES))})")
    return sorted(files, key=lambda p: _natural_key(p.name))


def sequence_info(source: str, files: list[Path], fps: float | None,
                  times_s: np.ndarray | None) -> tuple[VideoInfo, np.ndarray | None, list[str]]:
    """An image sequence's info, the frame times to use (None: ``index / fps``) and warnings: the
    clock is ``times_s``, else the EXIF capture times, else ``fps``; with ``fps`` given, EXIF times
    that disagree by more than 1% are warned of.

    Raises:
        InputError: the first image cannot be read, the times do not fit, or there is no clock.
    """
    from rotrate_cli.video.clock import exif_focal_px, exif_times  # Pillow only for photographs

    first = cv2.imread(str(files[0]), cv2.IMREAD_COLOR)
    if first is None:
        raise InputError(f"could not read the image {files[0]}; is it a picture file?")
    height, width = first.shape[:2]
    focal_px = exif_focal_px(files[0], width)
    if times_s is not None:
        if len(times_s) != len(files):
            raise InputError(f"`times_s` gives {len(times_s)} times for {len(files)} images; "
                             "give one time per image")
        return (VideoInfo(source, width, height, mean_rate(times_s), len(files), True, True, "times file", 0.0,
                          focal_px), times_s, [])
    exif = exif_times(files)
    if fps is None:
        if exif is None or exif.times_s is None:
            raise InputError("an image sequence has no frame rate and its images carry no capture times; "
                             "pass `fps` (frames per second) or `times_s` (one time per image)")
        return (VideoInfo(source, width, height, mean_rate(exif.times_s), len(files), True, False, "exif",
                          exif.resolution_s, focal_px), exif.times_s, [])
    notes = []
    if exif is not None and exif.times_s is not None:
        exif_rate = mean_rate(exif.times_s)
        if abs(exif_rate / fps - 1.0) > 0.01:
            notes.append(f"`fps={fps:g}` differs from the images' EXIF capture times ({exif_rate:.4g} "
                         "frames/s on average); the times used are index / `fps`")
    return VideoInfo(source, width, height, float(fps), len(files), True, True, "fps", 0.0, focal_px), None, notes


def sequence_frames(files: list[Path], info: VideoInfo, times_s: np.ndarray | None, start_s: float,
                    end_s: float | None, convert: Callable[[np.ndarray], Any]) -> Iterator[Frame]:
    """The images whose time lies in ``[start_s, end_s]``, converted, one at a time.

    Raises:
        InputError: an image that cannot be read, or of another size than the first.
    """
    for index, file in enumerate(files):
        time_s = float(times_s[index]) if times_s is not None else index / info.fps
        if time_s < start_s - 1e-9:
            continue
        if end_s is not None and time_s > end_s + 1e-9:
            return
        image = cv2.imread(str(file), cv2.IMREAD_COLOR)
        if image is None:
            raise InputError(f"could not read the image {file}")
        if image.shape[:2] != (info.height_px, info.width_px):
            raise InputError(f"the image {file} is {image.shape[1]}x{image.shape[0]}, not the sequence's "
                             f"{info.width_px}x{info.height_px}")
        yield Frame(index, time_s, convert(image))
