"""The case file: a whole computation in TOML, read, checked and built into a run.

:mod:`~breakwater.casefile.case` (the case and :func:`~breakwater.casefile.case.load_case`),
:mod:`~breakwater.casefile.loads` (the ``[loads.*]`` tables),
:mod:`~breakwater.casefile.loadchecks` and :mod:`~breakwater.casefile.godaface`
(loads checked against the mesh), :mod:`~breakwater.casefile.build` (case → model, specs).
"""
