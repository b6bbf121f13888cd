"""Tracks' samples placed again by matching each track's first patch, affinely warped: the lens
fit's (:mod:`rotrate_cli.scene.focal`) and the turning plane's (:mod:`rotrate_cli.scene.plane_turn`).

Lucas-Kanade follows a window by its translation alone, frame to frame. On a curved surface the
window's picture also turns, shears and shrinks as the surface turns, and the translation that
best explains a deformed window is not quite the motion of its centre: the error is small at
each step and adds up. Measured against a rendered sphere's own surface points (2026-11-24), the
tracks drifted a median 6.7 px over their lives, away from the equator while a point came into
view and back as it left, in step with its nearness: just the bob through a pinhole by which the
lens is found (:mod:`rotrate_cli.scene.focal`), so a 20-degree lens was found at 26.8 degrees and the
sphere read 2% slow.

Here each chosen track's patch at its first kept frame is the template, and at each later kept
frame the affine warp (and the brightness's gain and offset) that best matches it is found by
OpenCV's enhanced correlation coefficient (:func:`cv2.findTransformECC`), starting from the
tracker's position and the previous sample's warp. Matching against the first patch, not the
previous frame's, nothing adds up; the warp takes up the patch's deformation. Samples the match
moves far from the tracker's position, or matches poorly (a correlation under 0.9: the 10th
percentile on the accuracy suite's renders), are left out.

Measured on the accuracy suite's lenses (`make bench-accuracy`, 2026-11-24; found before ->
after, true): sphere 26.8 -> 19.9 (20), box 13.3 -> 14.9 (15), cylinder 25.0 -> 24.6 (25),
off-axis box 28.3 -> 29.4 (30), box from 30 degrees above 25.0 -> 25.2 (25); the sphere's rate
-2.00% -> +0.36%. The tracks' misfit to the rigid turn fell from 0.5-0.8 px rms to about 0.1.
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor

import cv2
import numpy as np

from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.tracking.keyframes import Keyframes

#: The template is a square of 2 PATCH_HALF_PX + 1 tracking pixels about the first sample.
PATCH_HALF_PX = 8
#: It is sought within this many pixels beyond its own size about the tracker's position.
SEARCH_MARGIN_PX = 6
#: A sample the match moves farther than this from the tracker's position (tracking pixels), or
#: whose correlation with the template is under MIN_CORRELATION, is left out. Correlations on the
#: accuracy suite's renders: median 0.98-0.995, 10th percentile 0.90-0.96; on real stills 3-10
#: degrees apart (the dinosaur, the EPFL cars), median 0.85-0.95, where the picture changes by
#: more than a warp (relief, gloss), and most tracks then fall short (see
#: :data:`rotrate_cli.scene.focal.PLACED_SHARE`).
MAX_SHIFT_PX = 3.0
MIN_CORRELATION = 0.9
#: The match stops after this many iterations or a step this small (in the warp's terms).
CRITERIA = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 20, 1e-3)


def place_again(keyframes: Keyframes, frame: np.ndarray, x_px: np.ndarray,
                y_px: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One track's samples (full-resolution pixels, at frames whose images are kept) placed
    again by matching its first sample's patch; NaN where the match failed or strayed."""
    scale = keyframes.scale
    seen_x, seen_y = x_px.astype(np.float64), y_px.astype(np.float64)
    if keyframes.camera is not None:
        # steadied positions: match where the shaken camera saw them
        seen_x, seen_y = keyframes.camera.redo(frame, seen_x, seen_y)
    x, y = seen_x * scale, seen_y * scale
    out_x, out_y = np.full(len(frame), np.nan), np.full(len(frame), np.nan)
    side = 2 * PATCH_HALF_PX + 1
    first = keyframes.image(frame[0])
    if not _inside(first, x[0], y[0], PATCH_HALF_PX + 1):
        return out_x, out_y
    template = cv2.getRectSubPix(first, (side, side), (float(x[0]), float(y[0]))).astype(np.float32)
    if float(template.std()) < 1.0:
        return out_x, out_y  # no texture to match
    out_x[0], out_y[0] = x[0], y[0]
    linear = np.eye(2, dtype=np.float32)
    reach = PATCH_HALF_PX + SEARCH_MARGIN_PX
    centre = np.array([PATCH_HALF_PX, PATCH_HALF_PX], np.float32)
    for k in range(1, len(frame)):
        image = keyframes.image(frame[k])
        left, top = int(round(x[k])) - reach, int(round(y[k])) - reach
        if left < 0 or top < 0 or left + 2 * reach + 1 > image.shape[1] or top + 2 * reach + 1 > image.shape[0]:
            continue
        window = image[top:top + 2 * reach + 1, left:left + 2 * reach + 1].astype(np.float32)
        warp = np.empty((2, 3), np.float32)
        warp[:, :2] = linear
        warp[:, 2] = np.array([x[k] - left, y[k] - top], np.float32) - linear @ centre
        try:
            correlation, warp = cv2.findTransformECC(template, window, warp, cv2.MOTION_AFFINE, CRITERIA, None, 1)
        except cv2.error:
            continue  # the match did not converge
        placed = warp[:, :2] @ centre + warp[:, 2]
        placed_x, placed_y = float(placed[0]) + left, float(placed[1]) + top
        if correlation < MIN_CORRELATION or math.hypot(placed_x - x[k], placed_y - y[k]) > MAX_SHIFT_PX:
            continue
        linear = warp[:, :2].copy()
        out_x[k], out_y[k] = placed_x, placed_y
    out_x, out_y = out_x / scale, out_y / scale
    if keyframes.camera is not None:
        out_x, out_y = keyframes.camera.undo(frame, out_x, out_y)
    return out_x, out_y


#: OpenCV lets go of the interpreter while it matches: this many tracks are placed at once.
PLACING_THREADS = 2


def place_tracks(keyframes: Keyframes, samples: pd.DataFrame, most_samples: int) -> pd.DataFrame:
    """``samples`` (``frame, time_s, track, x_px, y_px``, sorted by track then frame) at the
    frames kept in ``keyframes``, every track placed again (:func:`place_again`); where they hold
    more than ``most_samples`` samples, at every second, third, ... of those frames (evenly over
    the clip, every track kept: the tracks reach all over the body). The samples that did not
    match are left out."""
    samples = samples[keyframes.has(samples["frame"].to_numpy())]
    if len(samples) > most_samples:
        frames = np.unique(samples["frame"].to_numpy())
        every = math.ceil(len(samples) / most_samples)
        samples = samples[np.isin(samples["frame"].to_numpy(), frames[::every])]
    if len(samples) == 0:
        return samples
    track = samples["track"].to_numpy()
    starts = np.flatnonzero(np.r_[True, track[1:] != track[:-1]])
    ends = np.r_[starts[1:], len(track)]
    frame = samples["frame"].to_numpy()
    x, y = samples["x_px"].to_numpy(np.float64), samples["y_px"].to_numpy(np.float64)

    def place(k: int) -> tuple[np.ndarray, np.ndarray]:
        return place_again(keyframes, frame[starts[k]:ends[k]], x[starts[k]:ends[k]], y[starts[k]:ends[k]])

    with ThreadPoolExecutor(max_workers=PLACING_THREADS) as pool:
        placed = list(pool.map(place, range(len(starts))))
    new_x = np.concatenate([placed_x for placed_x, _ in placed])
    new_y = np.concatenate([placed_y for _, placed_y in placed])
    out = samples.assign(x_px=new_x, y_px=new_y)
    return out[np.isfinite(new_x) & np.isfinite(new_y)].reset_index(drop=True)


def _inside(image: np.ndarray, x: float, y: float, margin: int) -> bool:
    return margin <= x < image.shape[1] - margin and margin <= y < image.shape[0] - margin

