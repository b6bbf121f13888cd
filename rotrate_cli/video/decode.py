"""Video and image-sequence decoding, streamed frame by frame.

A :class:`FrameSource` opens a video file (anything OpenCV's FFmpeg backend reads), a printf
pattern of images (``frames/viff.%03d.png``) or a folder of images in natural name order, and
yields :class:`Frame` objects one at a time, so memory does not grow with the length of the clip.
Frame times come from the decoder's timestamps; where a container has none (or an image sequence
has no rate) they fall back to ``index / fps``, and a user-given ``fps`` always overrides.
"""

from __future__ import annotations

import math
import queue
import threading
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from rotrate_cli.errors import InputError
from rotrate_cli.video.container import mp4_damage, mp4_duration_s
from rotrate_cli.video.frames import Frame, VideoInfo, mean_rate
from rotrate_cli.video.luma import LUMA_CODECS, luma_table, quiet_opencv
from rotrate_cli.video.sequence import image_files, sequence_frames, sequence_info

#: Frame rates outside this range are treated as missing or absurd.
MIN_FPS = 1e-3
MAX_FPS = 10_000.0


#: The fraction of the announced frames a file other than an MP4/MOV may lack without a warning.
ANNOUNCED_SLACK = 0.1
#: Failed frames in a row after which a video is taken to have ended (a damaged spot is a few).
MAX_FAILED_RUN = 48
#: Frames probed at the start of a video whose first frame decodes black (see :mod:`rotrate_cli.video.pipe`).
BLACK_PROBE = 12
def _check_fps(fps: float | None, what: str) -> None:
    if fps is not None and not (MIN_FPS <= fps <= MAX_FPS and math.isfinite(fps)):
        raise InputError(
            f"{what} frame rate {fps} is not usable; pass `fps` with a value between {MIN_FPS} and {MAX_FPS:g}"
        )


class FrameSource:
    """A video file or an image sequence, opened for streaming.

    Args:
        source: video path, printf image pattern, or folder of images.
        fps: frame rate override in frames per second; for image sequences without capture
            times in their EXIF, required (or ``times_s``).
        times_s: one time per frame (``--times``), instead of the source's own or ``fps``.

    Raises:
        InputError: the source does not exist, cannot be decoded, has no usable frame rate, or
            ``times_s`` does not fit it.
    """

    def __init__(self, source: str | Path, fps: float | None = None, times_s: np.ndarray | None = None) -> None:
        self._source = str(source)
        _check_fps(fps, "the given")
        if fps is not None and times_s is not None:
            raise InputError("give `fps` or `times_s`, not both")
        self._times = None if times_s is None else np.asarray(times_s, dtype=np.float64)
        self.warnings: list[str] = []
        self._files: list[Path] | None = None
        self._codec = ""  # the stream's FOURCC, upper case (a video's)
        self._pipe: str | None = None  # the FFmpeg program that decodes what OpenCV gives black
        #: the damaged spots seen so far: the times of the decoded frames either side of each
        self.damaged_s: list[tuple[float, float]] = []
        #: frames that could not be decoded between good ones, over all reads so far
        self.failed_frames = 0
        self._first_grey: np.ndarray | None = None  # a thumbnail of a video's first frame, to check its luma
        self._luma: tuple[np.ndarray | None] | None = None  # the checked luma table, once checked
        path = Path(self._source)
        if "%" in path.name or path.is_dir():
            self._files = image_files(self._source)
        elif not path.exists():
            raise InputError(f"no such file: {self._source}")
        elif not path.is_file():
            raise InputError(f"not a regular file: {self._source}")
        elif path.stat().st_size == 0:
            raise InputError(f"the file is empty: {self._source}")

        if self._files is not None:
            self.info, self._times, notes = sequence_info(self._source, self._files, fps, self._times)
            self.warnings.extend(notes)
            return

        capture = self._open_capture()
        try:
            ok, first = capture.read()
            if not ok or first is None:
                raise InputError(
                    f"could not decode {self._source} as a video; is it a video file (mp4, mov, avi, mkv)?"
                )
            container_fps = float(capture.get(cv2.CAP_PROP_FPS) or 0.0)
            count = int(capture.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
            fourcc = int(capture.get(cv2.CAP_PROP_FOURCC) or 0)
        finally:
            capture.release()
        self._codec = fourcc.to_bytes(4, "little").decode("latin-1").strip("\x00 ").upper() if fourcc > 0 else ""
        if fps is None:
            if not (MIN_FPS <= container_fps <= MAX_FPS and math.isfinite(container_fps)):
                raise InputError(f"could not read the frame rate of {self._source}; pass `fps`")
        elif MIN_FPS <= container_fps <= MAX_FPS and abs(fps / container_fps - 1.0) > 0.01:
            # a slow-motion clip is a fair reason; a variable-rate phone video is not (+47% seen)
            self.warnings.append(f"`fps={fps:g}` differs from the stream's own rate ({container_fps:.4g} frames/s); "
                                 "the times used are index / `fps`")
        height, width = first.shape[:2]
        if first.max() == 0:
            first = self._black_start(first, width, height)
        self._first_grey = _grey(first)[::4, ::4]
        if self._times is not None and count > 0 and len(self._times) != count:
            raise InputError(f"`times_s` gives {len(self._times)} times but {self._source} announces {count} frames; "
                             "give one time per frame")
        if self._times is not None:
            rate = mean_rate(self._times)
        else:
            rate = float(fps if fps is not None else container_fps)
        self.info = VideoInfo(
            self._source,
            width,
            height,
            rate,
            count if count > 0 else None,
            False,
            fps is not None or self._times is not None,
            "times file" if self._times is not None else "fps" if fps is not None else "container",
        )

    def _starts_black(self) -> bool:
        """True when the first :data:`BLACK_PROBE` frames (or all, if fewer) decode all black."""
        capture = self._open_capture()
        try:
            for _ in range(BLACK_PROBE):
                ok, image = capture.read()
                if not ok or image is None:
                    return True
                if image.max() > 0:
                    return False
            return True
        finally:
            capture.release()

    def _black_start(self, first: np.ndarray, width: int, height: int) -> np.ndarray:
        """A video whose first frame OpenCV decodes black: read through FFmpeg where FFmpeg shows
        a picture there (an interlaced stream, see :mod:`rotrate_cli.video.pipe`), with a warning;
        without FFmpeg, said to the user when the first frames stay black. (OpenCV itself is no
        judge: on an interlaced H.264 file, the first two openings in a process gave black frames
        and the later ones pictures.) Returns the first frame to use."""
        from rotrate_cli.video.pipe import ffmpeg_program, first_frame

        program = ffmpeg_program()
        piped = first_frame(program, self._source, width, height) if program is not None else None
        if piped is not None and piped.max() > 0:
            self._switch_to_ffmpeg(program)
            return piped
        if program is None and self._starts_black():
            self.warnings.append(f"the first frames of {self._source} decode black; if the video is not black there "
                                 "it is probably interlaced, which this OpenCV decodes as black: deinterlace it "
                                 "(ffmpeg -i IN -vf yadif OUT.mp4), or put an ffmpeg on the PATH")
        return first

    def looks_undecoded(self, image: np.ndarray) -> bool:
        """True when a video's frame (BGR or grey) looks like what OpenCV gives for an interlaced
        stream it cannot convert, rather than a picture: black, or under half as bright as the
        first frame (mostly black, with a garbled band). A picture that truly darkens is read again
        through FFmpeg by a caller that asks, and comes out the same."""
        if self._files is not None or self._first_grey is None or self._pipe is not None:
            return False
        grey = _grey(image)
        first = float(self._first_grey.mean())
        return not grey.any() or float(grey[::4, ::4].mean()) < 0.5 * first

    def _switch_to_ffmpeg(self, program: str) -> None:
        """Read the video through ``program`` (FFmpeg) from now on, and say so once."""
        self._pipe, self._codec = program, "PIPE"
        self.warnings.append("OpenCV decodes this video's frames black or frozen (an interlaced stream: camcorder, "
                             "broadcast, DV?); it is read through FFmpeg instead, deinterlaced")

    def use_ffmpeg(self, only_if_interlaced: bool = False) -> bool:
        """Read the video through FFmpeg from now on (see :mod:`rotrate_cli.video.pipe`), for a caller
        that got nothing from OpenCV: True when it can be, and was not already. With
        ``only_if_interlaced``, only where FFmpeg says the stream is interlaced, which OpenCV
        decodes black or garbled in some openings and not others (for a caller that reads a
        single frame and cannot judge it by the frames around it)."""
        from rotrate_cli.video.pipe import ffmpeg_program, interlaced

        program = ffmpeg_program() if self._files is None and self._pipe is None else None
        if program is None or (only_if_interlaced and not interlaced(program, self._source)):
            return False
        self._switch_to_ffmpeg(program)
        return True

    def _decodes_black(self, capture: cv2.VideoCapture, quiet: bool) -> bool:
        """True when this opening decodes the first frame black though the opening that read it
        first did not (the capture is at the first frame, grabbed)."""
        if self._pipe is not None or self._first_grey is None or self._first_grey.max() == 0:
            return False
        if quiet:
            with quiet_opencv():
                ok, image = capture.retrieve()
        else:
            ok, image = capture.retrieve()
        return bool(ok and image is not None and image.max() == 0)

    def _piped(self, start_s: float, end_s: float | None, convert: Callable[[np.ndarray], Any],
               switched: bool = False) -> Iterator[Frame]:
        """The frames through FFmpeg (see :meth:`_black_start`), timed ``index / fps`` or by
        ``--times``. ``switched``: OpenCV was found decoding black mid-way (see
        :meth:`_decodes_black`); FFmpeg takes over, or the user is told how to get the frames.

        Raises:
            InputError: switched, and there is no FFmpeg program.
        """
        from rotrate_cli.video.pipe import ffmpeg_program, piped_frames

        if switched:
            program = ffmpeg_program()
            if program is None:
                raise InputError(f"OpenCV decodes the frames of {self._source} black (an interlaced stream: camcorder, "
                                 "broadcast, DV?): deinterlace it (ffmpeg -i IN -vf yadif OUT.mp4), or reinstall "
                                 "imageio-ffmpeg (a dependency) or put an ffmpeg on the PATH")
            self._switch_to_ffmpeg(program)
        assert self._pipe is not None  # noqa: S101 - only called in pipe mode
        for index, image in enumerate(piped_frames(self._pipe, self._source, self.info.width_px,
                                                   self.info.height_px)):
            if self._times is not None:
                if index >= len(self._times):
                    raise InputError(f"`times_s` gives {len(self._times)} times but {self._source} has more frames; "
                                     "give one time per frame")
                time_s = float(self._times[index])
            else:
                time_s = index / self.info.fps
            if time_s < start_s - 1e-9:
                continue
            if end_s is not None and time_s > end_s + 1e-9:
                return
            yield Frame(index, time_s, convert(image))

    def _open_capture(self) -> cv2.VideoCapture:
        capture = cv2.VideoCapture(self._source, cv2.CAP_FFMPEG)
        if not capture.isOpened():
            capture.release()
            damage = mp4_damage(Path(self._source))
            if damage is not None:
                raise InputError(f"{self._source} is a damaged or truncated {damage}; it cannot be read (was the "
                                 "recording cut off? a tool such as untrunc can rebuild the index from a good file "
                                 "of the same camera)")
            raise InputError(f"could not open {self._source} as a video; is it a video file (mp4, mov, avi, mkv)?")
        return capture

    def frames(
        self,
        start_s: float = 0.0,
        end_s: float | None = None,
        transform: Callable[[np.ndarray], Any] | None = None,
        grey: bool = False,
        map_luma: bool = True,
    ) -> Iterator[Frame]:
        """Yield frames whose time lies in ``[start_s, end_s]``, in order, one at a time.

        ``transform`` is applied to each kept frame's pixels (BGR, or grey with ``grey``) before
        it is yielded (for example a reduction for tracking), so a caller that decodes in a
        background thread also converts there.

        With ``grey``, a video's frames come as the grey image ``cv2.COLOR_BGR2GRAY`` would give,
        but taken from the decoder's own luma plane where that checks out against the colour
        conversion on the first frame (see :meth:`luma_levels`): skipping the conversion to BGR
        and back saves about 40% of the decoding time. Otherwise they are converted from BGR.
        With ``map_luma=False`` the luma is handed over as it is, for a caller that applies
        :meth:`luma_levels` itself after reducing the image (cheaper than on the full frame).
        """
        convert = transform if transform is not None else (lambda image: image)
        if grey:
            luma_frames = self._luma_stream(start_s, end_s, convert, map_luma)
            if luma_frames is not None:
                yield from luma_frames
                return
            convert = _compose(_grey, convert)
        if self._files is not None:
            yield from sequence_frames(self._files, self.info, self._times, start_s, end_s, convert)
            return

        if self._pipe is not None:
            yield from self._piped(start_s, end_s, convert)
            return
        yield from self._video_frames(self._open_capture(), start_s, end_s, convert)

    def _video_frames(
        self, capture: cv2.VideoCapture, start_s: float, end_s: float | None, convert: Callable[[np.ndarray], Any],
        quiet: bool = False,
    ) -> Iterator[Frame]:
        """The frames of an open video capture between ``start_s`` and ``end_s``, converted;
        the capture is released at the end. ``quiet`` silences OpenCV's log while retrieving."""
        failed = 0  # frames that could not be decoded since the last good one
        try:
            index = -1
            last_time_s = -math.inf
            while True:
                if not capture.grab():
                    # a damaged spot: FFmpeg goes on after it (a clean end fails every time)
                    index += 1
                    failed += 1
                    if failed > MAX_FAILED_RUN:
                        return
                    continue
                index += 1
                time_s = self._frame_time_s(capture, index, last_time_s)
                if failed:
                    self._note_failed(failed, last_time_s, time_s)
                    failed = 0
                last_time_s = time_s
                if index == 0 and self._decodes_black(capture, quiet):
                    # OpenCV's interlaced trouble strikes some openings and not others: this one is
                    # black where the opening that read the first frame was not
                    capture.release()
                    yield from self._piped(start_s, end_s, convert, switched=True)
                    return
                if time_s < start_s - 1e-9:
                    continue
                if end_s is not None and time_s > end_s + 1e-9:
                    return
                if quiet:
                    with quiet_opencv():
                        ok, image = capture.retrieve()
                else:
                    ok, image = capture.retrieve()
                if not ok or image is None or image.shape[:2] != (self.info.height_px, self.info.width_px):
                    failed += 1
                    continue
                yield Frame(index, time_s, convert(image))
        finally:
            capture.release()

    def shortfall(self, decoded: int, last_time_s: float) -> str | None:
        """A warning when a whole read of the video (``decoded`` frames, the last at
        ``last_time_s``) ended well before the file says it does; None otherwise.

        An MP4/MOV is judged by its own duration (its ``mvhd``), against the last frame's time:
        a stream-copied trim announces the frames from the key frame before its cut, which it
        does not show (92 shown of 101 announced), and is not cut off. Other files are judged by
        the frames they announce, less those that could not be decoded, with room for
        :data:`ANNOUNCED_SLACK` of them (a variable-rate AVI announces dropped frames).
        """
        expected = self.info.frame_count
        if self._files is not None or not expected or decoded == 0:
            return None
        # with --fps or --times the frames' times are not the file's, so its duration says nothing
        duration_s = None if self.info.fps_overridden else mp4_duration_s(Path(self._source))
        step_s = 1.0 / self.info.fps
        if duration_s is not None and math.isfinite(last_time_s):
            if last_time_s + step_s >= duration_s - 2.0 * step_s:
                return None
            return (f"the last frame decoded is at {last_time_s:.2f} s of the {duration_s:.2f} s the file announces; "
                    "it may be cut off or damaged")
        missing = expected - decoded - self.failed_frames
        if missing <= max(2, ANNOUNCED_SLACK * expected):
            return None
        return f"decoded {decoded} of the {expected} frames the file announces; it may be cut off or damaged"

    def _note_failed(self, count: int, before_s: float, after_s: float) -> None:
        """Say that ``count`` frames between two decoded ones could not be decoded (and keep
        where: :attr:`damaged_s`)."""
        self.failed_frames += count
        if (before_s, after_s) not in self.damaged_s:
            self.damaged_s.append((before_s, after_s))
        where = (f"between {before_s:.2f} s and {after_s:.2f} s" if math.isfinite(before_s)
                 else f"before {after_s:.2f} s")
        note = f"{count} frame(s) of {self._source} could not be decoded {where} (a damaged spot); the rest were read"
        if note not in self.warnings:
            self.warnings.append(note)

    def _open_luma_capture(self) -> cv2.VideoCapture:
        with quiet_opencv():
            return cv2.VideoCapture(self._source, cv2.CAP_FFMPEG, [cv2.CAP_PROP_CONVERT_RGB, 0])

    def luma_levels(self) -> np.ndarray | None:
        """A 256-entry table taking the decoder's luma to ``COLOR_BGR2GRAY`` grey, or None when
        the decoder cannot give luma for this video (an image sequence, a pixel format other than
        planar 8-bit YUV, a rotated picture, or a first frame too flat to check).

        The grey of BGR is, up to rounding, a straight-line function of studio-range luma, since
        the chroma terms of the YUV-to-RGB conversion cancel in the grey weights; the line is
        fitted on the first frame, and the luma is used only where it fits within
        :data:`_LUMA_MAX_RMS` grey levels. None too for codecs whose luma is slower to have than
        the conversion (not in :data:`LUMA_CODECS`): their frames come converted from BGR.
        """
        if self._first_grey is None or self._codec not in LUMA_CODECS:
            return None
        if self._luma is None:
            capture = self._open_luma_capture()
            try:
                with quiet_opencv():
                    ok, luma = capture.read() if capture.isOpened() else (False, None)
            finally:
                capture.release()
            self._check_luma(luma if ok else None)
        return self._luma[0] if self._luma is not None else None

    def _check_luma(self, luma: np.ndarray | None) -> None:
        """Fit and cache the luma table from the decoder's luma of the first frame (see
        :meth:`luma_levels`); None cached when it does not check out."""
        size = (self.info.height_px, self.info.width_px)
        self._luma = (luma_table(luma, self._first_grey, size),)

    def _luma_stream(
        self, start_s: float, end_s: float | None, convert: Callable[[np.ndarray], Any], map_luma: bool
    ) -> Iterator[Frame] | None:
        """The frames from the decoder's luma, or None when the luma does not check out. When
        the stream starts at the first frame, that frame is the check (no second opening)."""
        if self._first_grey is None or self._codec not in LUMA_CODECS:
            return None
        if self._luma is None and start_s <= 0:
            raw = self._video_frames(self._open_luma_capture(), start_s, end_s, lambda luma: luma, quiet=True)
            first = next(raw, None)
            self._check_luma(first.image if first is not None and first.index == 0 else None)
            table = self._luma[0] if self._luma is not None else None
            if table is None or first is None:
                raw.close()
                return None
            mapped = _compose(lambda luma: cv2.LUT(luma, table), convert) if map_luma else convert

            def stream() -> Iterator[Frame]:
                yield Frame(first.index, first.time_s, mapped(first.image))
                for frame in raw:
                    yield Frame(frame.index, frame.time_s, mapped(frame.image))

            return stream()
        table = self.luma_levels()
        if table is None:
            return None
        mapped = _compose(lambda luma: cv2.LUT(luma, table), convert) if map_luma else convert
        return self._video_frames(self._open_luma_capture(), start_s, end_s, mapped, quiet=True)

    def _frame_time_s(self, capture: cv2.VideoCapture, index: int, last_time_s: float) -> float:
        if self._times is not None:
            if index >= len(self._times):
                raise InputError(f"`times_s` gives {len(self._times)} times but {self._source} has more frames; "
                                 "give one time per frame")
            return float(self._times[index])
        fallback = index / self.info.fps
        if self.info.fps_overridden:
            return fallback
        stamp_ms = capture.get(cv2.CAP_PROP_POS_MSEC)
        # Decoders without timestamps report 0 or go backwards; fall back to index / fps then.
        if not math.isfinite(stamp_ms) or stamp_ms < 0 or (index > 0 and stamp_ms / 1000.0 <= last_time_s):
            return fallback
        return stamp_ms / 1000.0


def _compose(
    first: Callable[[np.ndarray], np.ndarray], then: Callable[[np.ndarray], Any]
) -> Callable[[np.ndarray], Any]:
    return lambda image: then(first(image))


def _grey(image: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image


def prefetch(frames: Iterator[Frame], depth: int = 8) -> Iterator[Frame]:
    """Run a frame iterator in a background thread and yield its frames here.

    OpenCV releases the GIL while it decodes, so decoding (and any transform attached to the
    iterator) overlaps with the consumer's work. At most ``depth`` frames wait in the queue, so
    memory stays bounded. Exceptions from the decoder are re-raised in the consumer.
    """
    done = object()
    slots: queue.Queue[Any] = queue.Queue(maxsize=depth)
    stop = threading.Event()

    def produce() -> None:
        try:
            for frame in frames:
                while not stop.is_set():
                    try:
                        slots.put(frame, timeout=0.1)
                        break
                    except queue.Full:
                        continue
                if stop.is_set():
                    return
            slots.put(done)
        except BaseException as exc:  # noqa: BLE001 - handed to the consumer to re-raise
            slots.put(exc)

    worker = threading.Thread(target=produce, name="rotrate-decode", daemon=True)
    worker.start()
    try:
        while True:
            item = slots.get()
            if item is done:
                return
            if isinstance(item, BaseException):
                raise item
            yield item
    finally:
        stop.set()
        while worker.is_alive():
            try:
                slots.get_nowait()
            except queue.Empty:
                worker.join(timeout=0.05)
