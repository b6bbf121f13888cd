"""Reading pictures: video and image-sequence decoding, the FFmpeg pipe, containers, frame times,
shots, mains flicker, and the synthetic clips of known rate.

Machinery: nothing here imports a stage (:mod:`rotrate_cli.stages`) or the settings object.
"""
