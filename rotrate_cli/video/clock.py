"""Where frame times and the lens come from when a container does not say: the photographs'
own EXIF, or a file of times (``--times``).

A turntable photographed by hand, one picture at a time, has no frame rate; its pictures carry
their capture times (DateTimeOriginal, with SubSecTimeOriginal where the camera writes it) and
their lens (FocalLength with FocalLengthIn35mmFilm, or the focal-plane resolution). Pillow reads
them (imported only here, only when needed: it costs start-up time otherwise).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path

import numpy as np

from rotrate_cli.errors import InputError

#: EXIF tags (the Exif sub-IFD and the focal-plane unit codes).
_EXIF_IFD = 0x8769
_DATETIME_ORIGINAL = 36867
_SUBSEC_ORIGINAL = 37521
_FOCAL_LENGTH = 37386
_FOCAL_35MM = 41989
_PLANE_X_RESOLUTION = 41486
_PLANE_UNIT = 41488
_UNIT_MM = {2: 25.4, 3: 10.0, 4: 1.0, 5: 0.001}
#: The width of a 35 mm film frame, mm (FocalLengthIn35mmFilm is relative to it).
FILM_WIDTH_MM = 36.0


@dataclass(frozen=True)
class Clock:
    """Frame times and where they come from.

    Attributes:
        times_s: one time per frame, seconds from the first (None: ``index / fps``).
        source: ``container`` (a video's timestamps), ``fps`` (``index / fps``), ``exif``
            (the photographs' capture times) or ``times file`` (``--times``).
        resolution_s: how finely the times are known (0 where exact enough not to matter).
    """

    times_s: np.ndarray | None
    source: str
    resolution_s: float = 0.0


def read_times(path: str | Path) -> np.ndarray:
    """Times in seconds, one per line (a header line and ``#`` comments are skipped; in a CSV
    line the first field counts), strictly increasing, from the first.

    Raises:
        InputError: the file cannot be read, holds no number, or the times do not increase.
    """
    try:
        lines = Path(path).read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"could not read `times_s` file {path}: {exc.strerror or exc}") from None
    values: list[float] = []
    for number, line in enumerate(lines, start=1):
        text = line.split("#", 1)[0].split(",", 1)[0].strip()
        if not text:
            continue
        try:
            value = float(text)
        except ValueError:
            if not values and number == 1:
                continue  # a header
            raise InputError(f"`times_s` file {path}, line {number}: {text!r} is not a time in seconds") from None
        if not math.isfinite(value):
            raise InputError(f"`times_s` file {path}, line {number}: the time must be a finite number of seconds")
        values.append(value)
    if len(values) < 2:
        raise InputError(f"`times_s` file {path} holds {len(values)} time(s); give one time in seconds per frame")
    times = np.asarray(values, dtype=np.float64)
    steps = np.diff(times)
    if not (steps > 0).all():
        bad = int(np.flatnonzero(steps <= 0)[0])
        raise InputError(f"`times_s` file {path}: the times must increase; time {bad + 2} ({times[bad + 1]:g} s) "
                         f"is not after time {bad + 1} ({times[bad]:g} s)")
    return times - times[0]


def _exif(file: Path):  # a PIL.Image.Exif, or None
    from PIL import Image, UnidentifiedImageError  # imported here: only photographs need it

    try:
        with Image.open(file) as image:
            return image.getexif()
    except (OSError, UnidentifiedImageError):
        return None


def exif_times(files: list[Path]) -> Clock | None:
    """The photographs' capture times (None unless every file has one and they increase)."""
    times: list[float] = []
    resolution = 1.0
    for file in files:
        exif = _exif(file)
        if exif is None:
            return None
        sub = exif.get_ifd(_EXIF_IFD)
        stamp = sub.get(_DATETIME_ORIGINAL) or exif.get(306)  # DateTime where the original is missing
        if not isinstance(stamp, str):
            return None
        try:
            moment = datetime.strptime(stamp.strip().rstrip("\x00"), "%Y:%m:%d %H:%M:%S").timestamp()
        except ValueError:
            return None
        fraction = str(sub.get(_SUBSEC_ORIGINAL) or "").strip().rstrip("\x00")
        if fraction.isdigit():
            moment += float("0." + fraction)
            resolution = min(resolution, 10.0 ** -len(fraction))
        times.append(moment)
    values = np.asarray(times)
    if len(values) < 2 or not (np.diff(values) > 0).all():
        return None
    return Clock(values - values[0], "exif", resolution)


def exif_focal_px(file: Path, width_px: int) -> float | None:
    """The lens's focal length in pixels of an image ``width_px`` wide, from its EXIF: the focal
    length times the focal-plane resolution, else the 35 mm equivalent over a 36 mm wide frame;
    None where neither is there."""
    exif = _exif(file)
    if exif is None:
        return None
    sub = exif.get_ifd(_EXIF_IFD)
    try:
        equivalent = float(sub.get(_FOCAL_35MM) or 0.0)
        focal_mm = float(sub.get(_FOCAL_LENGTH) or 0.0)
        plane_px = float(sub.get(_PLANE_X_RESOLUTION) or 0.0)
        unit_mm = _UNIT_MM.get(int(sub.get(_PLANE_UNIT) or 2), 25.4)
    except (TypeError, ValueError, ZeroDivisionError):
        return None
    if focal_mm > 0 and plane_px > 0:
        # the resolution is of the full-size picture: the EXIF image width scales it to this one
        full_width = float(sub.get(40962) or width_px)
        return focal_mm * plane_px / unit_mm * width_px / full_width
    if equivalent > 0:  # rounded to whole millimetres by most cameras: a few percent
        return equivalent / FILM_WIDTH_MM * width_px
    return None
