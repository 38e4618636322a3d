"""The case file: a whole computation in TOML, read, checked and built into a run.

Reading needs no solver stack (no dolfinx, PETSc or UFL):
:mod:`~breakwater.casefile.case` (:class:`~breakwater.casefile.case.Case` and
:func:`~breakwater.casefile.case.load_case`), :mod:`~breakwater.casefile.settings` (the
whole case and its cross-checks), :mod:`~breakwater.casefile.tables` (its tables) and
:mod:`~breakwater.casefile.loads` (the ``[loads.*]`` tables). Building needs it:
:mod:`~breakwater.casefile.build` (case → model, specs),
:mod:`~breakwater.casefile.meshloads` (the loads on a mesh),
:mod:`~breakwater.casefile.loadchecks` and :mod:`~breakwater.casefile.godaface` (loads
checked against the mesh).
"""
