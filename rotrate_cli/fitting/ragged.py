"""Many tracks of different lengths stored end to end, with per-track sums.

The estimators that fit every track at once at a trial rate (the joint fit, the axis
refinement) need, per track, sums such as ``sum(cos(omega t) * offset)``. Padding the tracks
into a rectangle wastes memory and time in proportion to the longest track; here the samples
stay end to end (sorted by track), each per-track sum is one ``np.add.reduceat``, and the trig
of a trial rate is taken once per distinct sample time rather than once per sample (tracks of
one video share the frames' times).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from rotrate_cli.runtime.lazy import pandas as pd


@dataclass(frozen=True)
class Ragged:
    """Tracks end to end.

    Attributes:
        ids: the track ids, in storage order (k,).
        starts: each track's first row (k,).
        counts: each track's number of samples (k,), all at least 1.
        offset: the samples' offsets (N,), in the source's units.
        time_index: each sample's index into ``times`` (N,).
        times_s: the distinct sample times, seconds (per frame when the samples have a
            ``frame`` column; frames without samples hold NaN).
    """

    ids: np.ndarray
    starts: np.ndarray
    counts: np.ndarray
    offset: np.ndarray
    time_index: np.ndarray
    times_s: np.ndarray

    @classmethod
    def from_samples(cls, samples: pd.DataFrame, tracks: np.ndarray | None = None) -> Ragged:
        """From ``samples`` (columns ``track, time_s, offset_px`` and optionally ``frame``,
        sorted by track then time), keeping only the ``tracks`` listed (all when None)."""
        track = samples["track"].to_numpy()
        keep = slice(None) if tracks is None else np.isin(track, tracks)
        track = track[keep]
        if len(track) == 0:
            empty = np.empty(0, dtype=np.int64)
            return cls(empty, empty, empty, np.empty(0), empty.astype(np.int32), np.empty(0))
        starts = np.flatnonzero(np.r_[True, track[1:] != track[:-1]])
        counts = np.diff(np.r_[starts, len(track)])
        ids = track[starts]
        del track
        time_s = samples["time_s"].to_numpy(dtype=float)
        frame = samples["frame"].to_numpy() if "frame" in samples.columns else None
        if frame is not None and len(frame) and int(frame.max()) - int(frame.min()) < 4 * len(frame) + 1000:
            # one time per frame: the frame number is the index into the frames' times
            first = int(frame.min())
            times_s = np.full(int(frame.max()) - first + 1, np.nan)
            times_s[frame - first] = time_s
            time_index = frame[keep].astype(np.int32)
            time_index -= first
            if _consistent(times_s, time_index, time_s[keep] if tracks is not None else time_s):
                return cls(ids, starts, counts, samples["offset_px"].to_numpy(dtype=float)[keep], time_index,
                           times_s)
        # hashing, not sorting: a long clip's samples are factorised without sorted copies
        codes, unique_s = pd.factorize(time_s[keep], sort=True)
        offset = samples["offset_px"].to_numpy(dtype=float)[keep]
        return cls(ids, starts, counts, offset, codes.astype(np.int32), np.asarray(unique_s, dtype=float))

    def __len__(self) -> int:
        return len(self.ids)

    @property
    def time_s(self) -> np.ndarray:
        """Each sample's time, seconds (N,)."""
        return self.times_s[self.time_index]

    def sums(self, values: np.ndarray) -> np.ndarray:
        """Per-track sums of per-sample ``values`` (k,)."""
        if len(values) == 0:
            return np.zeros(len(self.ids))
        return np.add.reduceat(values, self.starts)

    def spread(self, per_track: np.ndarray) -> np.ndarray:
        """A per-track value repeated over that track's samples (N,)."""
        return np.repeat(per_track, self.counts)

    def blocks(self, max_samples: int) -> Iterator[tuple[slice, Ragged]]:
        """Consecutive groups of whole tracks with about ``max_samples`` samples or fewer each (a
        longer track forms a group on its own), with the slice of ``ids`` each group holds:
        working in blocks keeps temporaries the same size however long the clip."""
        ends = self.starts + self.counts
        first = 0
        while first < len(self.ids):
            base = int(self.starts[first])
            last = max(int(np.searchsorted(ends, base + max_samples, side="right")), first + 1)
            stop = int(ends[last - 1])
            yield slice(first, last), Ragged(
                self.ids[first:last], self.starts[first:last] - base, self.counts[first:last],
                self.offset[base:stop], self.time_index[base:stop], self.times_s,
            )
            first = last


def _consistent(times_s: np.ndarray, time_index: np.ndarray, time_s: np.ndarray, block: int = 1 << 16) -> bool:
    """True when every sample's time is its frame's time (checked in blocks: no full-size
    temporaries)."""
    return all(np.array_equal(times_s[time_index[i:i + block]], time_s[i:i + block])
               for i in range(0, len(time_index), block))
