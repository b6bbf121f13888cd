"""What a video file's container says of itself, read without decoding: for an MP4/MOV/3GP,
its top-level boxes, whether its index (``moov``) is there and whole, and its duration from the
movie header. The decoder uses it to tell a truncated recording from a file that is no video,
and a file cut short from a stream-copied trim (which announces frames it does not show)."""

from __future__ import annotations

from pathlib import Path


def _mp4_boxes(path: Path) -> list[tuple[bytes, int, int, bool]] | None:
    """The top-level boxes of an MP4/MOV/3GP file as ``(type, offset, length, whole)``, or None
    when the file does not start with an ``ftyp`` box."""
    try:
        size = path.stat().st_size
        boxes = []
        with path.open("rb") as file:
            offset = 0
            while offset + 8 <= size and len(boxes) < 64:
                file.seek(offset)
                header = file.read(16)
                length, kind = int.from_bytes(header[:4], "big"), header[4:8]
                if length == 1 and len(header) >= 16:
                    length = int.from_bytes(header[8:16], "big")
                elif length == 0:
                    length = size - offset
                if length < 8 or not kind.isalnum():
                    break
                boxes.append((kind, offset, length, offset + length <= size))
                offset += length
    except OSError:
        return None
    return boxes if boxes and boxes[0][0] == b"ftyp" else None


def mp4_duration_s(path: Path) -> float | None:
    """An MP4/MOV's duration from its movie header (``moov/mvhd``), seconds; None where there
    is none to read."""
    boxes = _mp4_boxes(path)
    moov = next(((offset, length) for kind, offset, length, whole in boxes or [] if kind == b"moov" and whole), None)
    if moov is None:
        return None
    try:
        with path.open("rb") as file:
            file.seek(moov[0] + 8)
            inner = file.read(min(moov[1] - 8, 1 << 20))
    except OSError:
        return None
    at = 0
    while at + 8 <= len(inner):
        length, kind = int.from_bytes(inner[at:at + 4], "big"), inner[at + 4:at + 8]
        if kind == b"mvhd" and at + 32 <= len(inner):
            version = inner[at + 8]
            body = inner[at + 12:]
            if version == 1:
                timescale, duration = int.from_bytes(body[16:20], "big"), int.from_bytes(body[20:28], "big")
            else:
                timescale, duration = int.from_bytes(body[8:12], "big"), int.from_bytes(body[12:16], "big")
            return duration / timescale if timescale > 0 and duration > 0 else None
        if length < 8:
            return None
        at += length
    return None


def mp4_damage(path: Path) -> str | None:
    """What is wrong with a file that looks like an MP4/MOV/3GP but cannot be opened: its index
    (the ``moov`` box) missing or cut, as when a recording stops before the camera writes it;
    None when it does not look like one, or looks whole."""
    boxes = _mp4_boxes(path)
    if boxes is None:
        return None
    moov = [whole for kind, _, _, whole in boxes if kind == b"moov"]
    if moov and all(moov):
        return None
    return "MP4/MOV file: its index (the 'moov' box) is " + ("cut short" if moov else "missing")
