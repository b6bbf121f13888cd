"""The renderer: the rays left out of a body's intersections change no pixel, and frames
rendered ahead on threads are those rendered one by one."""

from __future__ import annotations

import numpy as np
import pytest

from rotrate_cli.video.synth import Renderer, SceneConfig

SCENES = {
    "box through a lens from above": SceneConfig(shape="box", omega_rad_s=0.5, projection="perspective", fov_deg=60.0,
                                                 elevation_deg=40.0, width_px=160, height_px=90, supersample=2),
    "two bodies, rolled": SceneConfig(shape="cylinder", omega_rad_s=0.5, second_shape="sphere",
                                      second_omega_rad_s=-0.3, axis_offset_px=-40, second_axis_offset_px=40,
                                      roll_deg=10.0, width_px=160, height_px=90, supersample=1),
    "cylinder filling a portrait frame": SceneConfig(shape="cylinder", omega_rad_s=-0.7, width_px=90, height_px=160,
                                                     projection="perspective", fov_deg=40.0, elevation_deg=-15.0,
                                                     object_height_fraction=0.95, supersample=1),
}


@pytest.mark.parametrize("name", list(SCENES))
def test_the_rays_left_out_change_no_pixel(name: str) -> None:
    renderer = Renderer(SCENES[name])
    culled = [renderer.render(k) for k in (0, 11, 40)]
    if not name.startswith("cylinder filling"):  # there every ray can meet it
        assert all(len(rays) < 0.5 * len(renderer._origin) for rays in renderer._rays)  # noqa: SLF001
    renderer._rays = [np.arange(len(renderer._origin)) for _ in renderer._rays]  # noqa: SLF001 - every ray
    for k, image in zip((0, 11, 40), culled, strict=True):
        assert np.array_equal(image, renderer.render(k))


def test_frames_rendered_ahead_on_threads_are_those_rendered_one_by_one() -> None:
    renderer = Renderer(SCENES["two bodies, rolled"])
    one_by_one = [renderer.render(k) for k in range(12)]
    for workers in (1, 3):
        ahead = list(renderer.frames(range(12), workers=workers))
        assert len(ahead) == 12 and all(np.array_equal(a, b) for a, b in zip(ahead, one_by_one, strict=True))
