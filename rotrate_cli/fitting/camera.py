"""The pinhole camera the perspective fits project through, about a fixation point.

The camera stage (:mod:`rotrate_cli.stages.camera`) decides the lens; this is the model the
estimators, the joint fit and the axis search use.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Camera:
    """A pinhole camera, for perspective fits.

    Attributes:
        focal_px: focal length in pixels (from the field of view: ``(width / 2) / tan(fov / 2)``).
        axis_n: the axis's horizontal image position relative to the principal point (the image
            centre), divided by the focal length.
        depth_scale: the cosine of the camera's elevation (1 for a level camera). Seen from
            above, a point's depth changes by its radial position times this cosine, while its
            height only changes its distance by a constant per track (taken up by its amplitude).
        sense: +1 anticlockwise, -1 clockwise where the view told it (the lens's fit, seen
            from above: :attr:`rotrate_cli.scene.focal.FocalEstimate.sense`); 0 where the tracks'
            fits are to tell it.
    """

    focal_px: float
    axis_n: float
    depth_scale: float = 1.0
    sense: int = 0



def focal_px_from_fov(fov_deg: float, width_px: int) -> float:
    """The focal length in pixels of a horizontal field of view ``fov_deg`` over ``width_px``."""
    return (width_px / 2.0) / math.tan(math.radians(fov_deg) / 2.0)
