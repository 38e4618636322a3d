"""Typed settings and their TOML form: the schema machinery and the run specs.

:mod:`~breakwater.config.schema` reads frozen dataclasses from TOML (types, units,
ranges, unknown keys); :mod:`~breakwater.config.runspec` holds the time, output,
probe and initial-state specs that the case file fills and the run consumes.
"""
