"""breakwater: dynamic frictional contact of deformable bodies with FEniCSx.

The PyPI wheel ``dolfinx-solver-real`` ships PETSc inside the package
``dolfinx_solver``, which must be imported before dolfinx and petsc4py. It is an
optional extra: with a conda-forge dolfinx it is absent and nothing is needed.
"""

from __future__ import annotations

import importlib.util

if importlib.util.find_spec("dolfinx_solver") is not None:  # pragma: no branch
    import dolfinx_solver  # noqa: F401

__version__ = "0.1.0"
