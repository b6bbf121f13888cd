"""Following points through frames: Lucas-Kanade corners (klt), CSRT, user-chosen points, a
hand-held camera's shake, the tracker's keyframes and tracks read from a file.

Machinery: nothing here imports a stage (:mod:`rotrate_cli.stages`) or the settings object.
"""
