"""Runtime helpers every layer may use: deferred imports, thread pools, memory, the CLI's choice names.

Machinery: nothing here imports a stage (:mod:`rotrate_cli.stages`) or the settings object.
"""
