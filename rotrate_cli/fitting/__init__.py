"""Fitting and statistics: per-sample and per-track rate estimators, the joint fit, outlier
rejection, omega(t), grouping tracks into bodies, and small statistics.

Machinery: nothing here imports a stage (:mod:`rotrate_cli.stages`) or the settings object.
"""
