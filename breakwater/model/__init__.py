"""The contact model: a gmsh mesh with named groups, bodies, materials, pairs and loads.

:mod:`~breakwater.model.mesh` reads the mesh and its physical names;
:mod:`~breakwater.model.model` builds the function spaces, the UFL residual and the
contact pairs that every later stage (statics, stepping, outputs) works on.
"""
