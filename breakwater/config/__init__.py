"""Typed settings and their TOML form: the schema machinery and the run specs.

:mod:`~breakwater.config.schema` reads frozen dataclasses from TOML files (``extends``,
path values, the origin of each key), with :mod:`~breakwater.config.fields` (declaring,
checking and typing fields), :mod:`~breakwater.config.tomlfiles` (reading and merging
files), :mod:`~breakwater.config.convert` (TOML data to dataclasses),
:mod:`~breakwater.config.overrides` (``--set``) and :mod:`~breakwater.config.reference`
(the table of every key); :mod:`~breakwater.config.runspec` holds the time, output,
probe and initial-state specs that the case file fills and the run consumes.
"""
