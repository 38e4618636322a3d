"""The bodies' mean rotation: a history column per body, and the small-rotation check.

The model is linear elasticity (small strains), as the paper's: its strain-free motions
are the infinitesimal ones, u = c + φ e_z × x, which for a finite φ is no rotation: each
point moves along the tangent instead of the arc, the body grows by √(1 + φ²) − 1 ≈
φ²/2 (and a true rotation would cost the strain φ²/2, with its stresses), and the
displacements are off the arc by about φ/2 of themselves. A caisson that rocks by
0.01 rad is within the model; a block that topples or a cylinder that rolls is not, and
its numbers are wrong without any other sign (a cylinder rolling down a 30° slope, 1.3
rad in 0.2 s, grew into the slope, was pushed off it and flew: measured). So each step
records each body's mean rotation,

    ω = (1/V) ∫ ½ (∂u_y/∂x − ∂u_x/∂y) dx     (counter-clockwise, rad),

in 3D the magnitude of the mean of ½ curl u: φ for u = c + φ e_z × x, exactly on any
mesh (a linear field, which the elements hold). ω is a linear functional of u: the
vector b = ∫ ½ curl(v) dx / V is assembled once per body (and component) and each step
takes b · u (one reduction for all bodies).

:func:`rotation_warning` names the body that rotated past :data:`LIMIT` (the run's
summary: ``dynamic.max_rotation``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import ufl
from dolfinx import fem, la
from mpi4py import MPI

from breakwater.model.model import ContactModel
from breakwater.outputs import historyrows

__all__ = ["LIMIT", "Rotations", "rotation_warning"]

LIMIT = 0.05
"""The rotation (rad) beyond which a run is warned: its displacements off by φ/2 = 2.5 %,
the body grown by φ²/2 = 1.25e-3 (beyond a concrete structure's elastic strains)."""


class Rotations:
    """Each body's mean rotation ω (the module doc): the ``<body>_rotation`` columns.

    Args:
        model: The contact model.
    """

    def __init__(self, model: ContactModel) -> None:
        self.comm = model.comm
        self.names = [b.spec.name for b in model.bodies]
        self.columns = [f"{name}_rotation" for name in self.names]
        self._b: list[list[np.ndarray]] = []
        self._owned: list[int] = []
        for body in model.bodies:
            v = ufl.TestFunction(body.V)
            curl = ufl.curl(v) if model.gdim == 3 else ufl.as_vector(
                [v[1].dx(0) - v[0].dx(1)])
            volume = self.comm.allreduce(fem.assemble_scalar(fem.form(
                fem.Constant(body.submesh, 1.0) * ufl.dx(domain=body.submesh))))
            index_map, bs = body.V.dofmap.index_map, body.V.dofmap.index_map_bs
            n = index_map.size_local * bs
            vectors = []
            for k in range(curl.ufl_shape[0]):
                b = fem.assemble_vector(fem.form(0.5 * curl[k] / volume * ufl.dx))
                b.scatter_reverse(la.InsertMode.add)
                vectors.append(np.array(b.array[:n]))
            self._b.append(vectors)
            self._owned.append(n)

    def values(self, u: Sequence[fem.Function]) -> dict[str, float]:
        """The columns at the state ``u`` (one Function per body; collective)."""
        local = [float(b @ f.x.array[:n]) for f, bs, n in zip(u, self._b, self._owned,
                                                               strict=True) for b in bs]
        total = np.array(local)
        self.comm.Allreduce(MPI.IN_PLACE, total, op=MPI.SUM)
        out, k = {}, 0
        for column, bs in zip(self.columns, self._b, strict=True):
            ω = total[k:k + len(bs)]
            out[column] = float(ω[0]) if len(bs) == 1 else float(np.linalg.norm(ω))
            k += len(bs)
        return out


def largest(rows: Sequence[Mapping[str, float]], bodies: Sequence[str]
            ) -> dict[str, dict[str, float]]:
    """Each body's largest |ω| over the history rows, and when (the first).

    The columns are read whole (:func:`~breakwater.outputs.historyrows.column`): a loop
    over the rows, at every checkpoint's summary, took half of a run's time with a
    checkpoint every step (69 s of 139 s over 3000 steps).
    """
    out = {}
    t = historyrows.column(rows, "t")
    for name in bodies:
        ω = np.abs(historyrows.column(rows, f"{name}_rotation"))
        k = int(np.argmax(ω))
        out[name] = {"value": float(ω[k]), "time": float(t[k])}
    return out


def rotation_warning(dynamic: Mapping[str, Any]) -> str | None:
    """The warning of a run whose body rotated past :data:`LIMIT`, or None.

    Args:
        dynamic: The summary's ``dynamic`` entry (its ``max_rotation``).
    """
    worst = max(dynamic.get("max_rotation", {}).items(), key=lambda kv: kv[1]["value"],
                default=None)
    if worst is None or worst[1]["value"] <= LIMIT:
        return None
    name, φ = worst[0], worst[1]["value"]
    return (f"body '{name}' rotates by {φ:.3g} rad ({np.degrees(φ):.3g}°) at t = "
            f"{worst[1]['time']:.4g} s: the model's linear (small-strain) elasticity holds "
            f"for small rotations only (a rotation φ grows the body by φ²/2, here "
            f"{0.5 * φ**2:.2g}, and puts its displacements off the arc by about φ/2, here "
            f"{50 * φ:.2g} %); past {LIMIT:g} rad these results are not reliable")
