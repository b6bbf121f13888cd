"""The pipeline's stages, in order. Each is a module taking the previous stage's typed result
and the settings it uses, and returning its own; :func:`rotrate_cli.analysis.analyze` is the
list of their calls.

1. :mod:`~rotrate_cli.stages.tracks`: source -> :class:`~rotrate_cli.stages.tracks.Footage`
   (decoded on its longest shot, points followed, the camera's shake taken out, thumbnails).
2. :mod:`~rotrate_cli.stages.period`: thumbnails -> :class:`~rotrate_cli.stages.period.Period`,
   how long until the picture comes back (runs beside 3-5).
3. :mod:`~rotrate_cli.stages.geometry`: tracks -> :class:`~rotrate_cli.stages.geometry.Geometry`
   (the axis's angle and place, the lens) and the body's offsets; then the fits about it with a
   found fixation refined (``locate``, ``measure``).
4. :mod:`~rotrate_cli.stages.camera`: the lens (given, EXIF, found or orthographic), asked by 3.
5. :mod:`~rotrate_cli.stages.fits`: offsets -> :class:`~rotrate_cli.stages.fits.RateResult`
   (per-track fits, outliers, one joint rate and its interval), asked by 3.
6. :mod:`~rotrate_cli.stages.checks`: every doubt about the tracks' rate, in one place ->
   :class:`~rotrate_cli.stages.checks.Checked`.
7. :mod:`~rotrate_cli.stages.verdict`: the tracks' rate and the period weighed ->
   :class:`~rotrate_cli.stages.verdict.Verdict` (the reported rate, ``good``/``weak``), with the
   picture's own turning angle (:mod:`~rotrate_cli.stages.angle`) asked for where the picture does
   not come back, or the count of its returns a turn is open.
8. :mod:`~rotrate_cli.stages.view_at_rate`: after the verdict, the view read from the paths at
   the reported rate (it needs the rate), and on a repetition-rated face-on body, the axis.

9. :mod:`~rotrate_cli.stages.windows`: with a window, omega(t) rated by the headline's source.

:mod:`~rotrate_cli.stages.bodies` runs 3-7 once per rigid body (``segment``).
"""
