"""Files written for the user: safe writing, and overlays drawn on the frames.

Machinery: nothing here imports a stage (:mod:`rotrate_cli.stages`) or the settings object.
"""
