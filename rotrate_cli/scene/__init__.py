"""Scene geometry found from the tracks: the axis, the view, the sense of turning, the lens, and
why tracks were rejected.

Machinery: nothing here imports a stage (:mod:`rotrate_cli.stages`) or the settings object.
"""
