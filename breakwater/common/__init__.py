"""Foundations every layer uses: errors, MPI helpers, output files, the console, gmsh.

Nothing here imports dolfinx or PETSc at module level, or any other part of breakwater.
"""
