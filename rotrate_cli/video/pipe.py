"""A second decoder for the videos OpenCV reads wrongly: frames piped from an FFmpeg program.

OpenCV 4.13 and later hand back all-black frames, and say they succeeded, for streams flagged
interlaced (camcorders, broadcast, DV, interlaced H.264): its colour conversion refuses
interlaced pictures, and its raw-plane path gives zeros too. FFmpeg's own program decodes them,
and deinterlaces them on the way (``yadif``, one frame per frame, only frames flagged
interlaced), so they measure as any other video. The program is the one ``imageio-ffmpeg``
ships (a dependency), else an ``ffmpeg`` on the PATH; without either (imageio-ffmpeg has no
binary for every platform), the user is told how to deinterlace the file.
"""

from __future__ import annotations

import shutil
import subprocess
from collections.abc import Iterator

import numpy as np

#: How to decode: every frame as packed BGR, deinterlaced where flagged interlaced.
_FILTER = "yadif=mode=send_frame:deint=interlaced"


def ffmpeg_program() -> str | None:
    """The FFmpeg program to pipe from, or None when there is none."""
    try:
        import imageio_ffmpeg
    except ImportError:
        return shutil.which("ffmpeg")
    try:
        return imageio_ffmpeg.get_ffmpeg_exe()
    except RuntimeError:  # its binary is missing on this platform
        return shutil.which("ffmpeg")


def piped_frames(program: str, source: str, width_px: int, height_px: int) -> Iterator[np.ndarray]:
    """The video's frames, in order, as BGR images of ``height_px x width_px`` (the decoder's
    size; frames of another size end the stream). The process is ended when the caller stops."""
    command = [program, "-nostdin", "-v", "error", "-i", source, "-map", "0:v:0", "-vf", _FILTER,
               "-f", "rawvideo", "-pix_fmt", "bgr24", "-"]
    size = width_px * height_px * 3
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, bufsize=size)
    try:
        assert process.stdout is not None  # noqa: S101 - asked for with PIPE
        while True:
            data = process.stdout.read(size)
            if len(data) < size:
                return
            yield np.frombuffer(bytearray(data), np.uint8).reshape(height_px, width_px, 3)  # writable
    finally:
        process.kill()
        process.wait()
        if process.stdout is not None:
            process.stdout.close()


#: How FFmpeg names the field order of an interlaced picture in its stream description.
_FIELD_ORDERS = ("(top first", "(bottom first", "(top coded first", "(bottom coded first")


def interlaced(program: str, source: str) -> bool:
    """True when FFmpeg describes the video's first stream as interlaced (its pixel format
    followed by a field order, ``yuv420p(top first)``)."""
    try:
        described = subprocess.run([program, "-hide_banner", "-nostdin", "-i", source], capture_output=True,
                                   text=True, errors="replace", timeout=30).stderr
    except (OSError, subprocess.SubprocessError):
        return False
    video = next((line for line in described.splitlines() if " Video: " in line), "")
    return any(order in video for order in _FIELD_ORDERS)


def first_frame(program: str, source: str, width_px: int, height_px: int) -> np.ndarray | None:
    """The video's first frame through FFmpeg, or None when it gives none."""
    return next(piped_frames(program, source, width_px, height_px), None)
