"""The forms and assembly helpers of a contact model, on the data the model builds.

:class:`ModelForms` holds what every stage asks of a built model: the bulk and
interface residuals (the paper's eqs. 1-4 and 23, in UFL: :mod:`forms`), and the
helpers that compile and assemble forms over the parent mesh with the bodies' entity
maps. :class:`~breakwater.model.model.ContactModel` builds the data it reads.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import dolfinx
import numpy as np
import ufl
from dolfinx import fem
from dolfinx.io import gmsh as gmshio
from mpi4py import MPI

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from breakwater.model.pairs import PairData
from breakwater.model.parts import BodyData, Damping, LoadData

__all__ = ["ModelForms"]


class ModelForms:
    """The residual forms and the assembly helpers of a built contact model.

    Attributes:
        mesh_data: The mesh and its groups.
        mesh: The parent mesh.
        comm: Its communicator.
        gdim: The geometric dimension.
        bodies: What the model built for each body.
        pairs: What it built for each conforming pair.
        loads: What it built for each load.
        entity_maps: The bodies' cell maps to the parent mesh.
        W: The mixed space of the bodies' displacements; ``w`` its test functions.
        gravity: Body force per unit mass (m/s²).
        damping: Rayleigh damping; ``α``, ``β`` its constants.

    """

    mesh_data: gmshio.MeshData
    mesh: dolfinx.mesh.Mesh
    comm: MPI.Comm
    gdim: int
    bodies: Sequence[BodyData]
    pairs: Sequence[PairData]
    loads: Sequence[LoadData]
    entity_maps: list[dolfinx.mesh.EntityMap]
    W: ufl.MixedFunctionSpace
    w: Sequence
    gravity: fem.Constant
    damping: Damping
    α: fem.Constant
    β: fem.Constant
    _solvers: int

    # --- physics ------------------------------------------------------------------

    def set_time(self, t: float) -> None:
        """Evaluate the time-dependent loads at time ``t`` (a staged field: its stage)."""
        for ld in self.loads:
            ld.amplitude.value = ld.spec.amplitude(t)
            ld.set_stage(t)

    def mass(self, a: Sequence, w: Sequence | None = None) -> ufl.Form:
        """Σ ∫ ρ a·w over the bodies (M a)."""
        w = self.w if w is None else w
        return sum(forms.inertia(b.ρ, a[i], w[i], b.dx) for i, b in enumerate(self.bodies))

    def stiffness(self, u: Sequence, w: Sequence | None = None) -> ufl.Form:
        """Σ ∫ σ(u):ε(w) over the bodies (K u)."""
        w = self.w if w is None else w
        return sum(forms.elastic_residual(u[i], w[i], b.λ, b.μ, b.dx)
                   for i, b in enumerate(self.bodies))

    def external_load(self, w: Sequence | None = None) -> ufl.Form:
        """Gravity and surface tractions at the current load time (f)."""
        w = self.w if w is None else w
        f = sum(forms.body_force(b.ρ, self.gravity, w[i], b.dx)
                for i, b in enumerate(self.bodies))
        for ld in self.loads:
            f += forms.surface_traction(ld.traction, w[ld.body], ld.ds)
        return f

    def bulk_residual(self, u: Sequence, v: Sequence | None = None,
                      a: Sequence | None = None) -> ufl.Form:
        """Linear bulk terms M a + C v + K u − f; ``v``/``a`` None for statics."""
        F = self.stiffness(u) - self.external_load()
        if a is not None:
            F += self.mass(a)
        if v is not None and (self.damping.alpha or self.damping.beta):
            F += sum(forms.rayleigh_damping(self.α, self.β, b.ρ, v[i], self.w[i], b.λ, b.μ, b.dx)
                     for i, b in enumerate(self.bodies))
        return F

    def traction(self, pair: PairData, u: Sequence, v: Sequence | None):
        """Contact traction on the slave of a pair (eq. 23); frictionless when ``v`` is None.

        The law is the pair's :class:`forms.ContactLaw` (see :mod:`forms.contact`).
        """
        us, um = u[pair.slave]("+"), u[pair.master]("-")
        if v is None:
            return pair.law.traction(us, um, pair.n)
        return pair.law.traction(us, um, pair.n, v[pair.slave]("+"), v[pair.master]("-"))

    def interface_residual(self, u: Sequence, v: Sequence | None = None) -> ufl.Form:
        """Contact terms of every pair; frictionless when ``v`` is None (statics)."""
        return sum(forms.contact_residual(self.traction(p, u, v), self.w[p.slave]("+"),
                                          self.w[p.master]("-"), p.dS) for p in self.pairs)

    def residual(self, u: Sequence, v: Sequence | None = None,
                 a: Sequence | None = None) -> ufl.Form:
        """The whole residual: bulk plus interface."""
        F = self.bulk_residual(u, v, a)
        if self.pairs:
            F += self.interface_residual(u, v)
        return F

    # --- helpers ------------------------------------------------------------------

    def functions(self, name: str) -> list[fem.Function]:
        """One new zero Function per body, named ``{name}_{body}``."""
        return [fem.Function(b.V, name=f"{name}_{b.spec.name}") for b in self.bodies]

    def load_resultant(self, ld: LoadData, i: int,
                       weight: Callable[[np.ndarray], np.ndarray] | None = None) -> ufl.Form:
        """∫ t_i ds of a load's unit traction, with its load vector's quadrature.

        The load vector is b = ∫ t · w ds with w the body's (P2) test functions, and the
        force it applies along i is the sum of its entries there, ∫ t · e_i ds with e_i
        the unit field of the body's space along i: the same quadrature, so this is what
        the run applies. ``∫ t_i ds`` alone is integrated with a lower degree (UFL
        estimates it from t), and a profile's jump or kink inside a facet (Goda's
        pressure at a crest that cuts it) makes the two differ: 9 % on a 25 mm facet.

        Args:
            ld: The load.
            i: The component.
            weight: A function of the points (shape (3, n)) whose nodal values weight the
                sum, Σ_k b_ik weight(x_k): e.g. a lever arm, for the moment the load
                vector applies (exact when the space reproduces the weight, as P2 does
                a linear one).
        """
        e = fem.Function(self.bodies[ld.body].V)
        if weight is None:
            e.x.array.reshape(-1, self.gdim)[:, i] = 1.0
        else:
            def along(x: np.ndarray) -> np.ndarray:
                out = np.zeros((self.gdim, x.shape[1]))
                out[i] = weight(x)
                return out
            e.interpolate(along)
        return ufl.dot(ld.unit, e) * ld.ds

    def options_prefix(self, name: str) -> str:
        """A new PETSc options prefix ``breakwater_<name>_<k>_`` for a solver of this model.

        ``k`` counts the solvers built on this model, so that each problem has its own
        prefix, the same on every rank and in every run.
        """
        prefix = f"breakwater_{name}_{self._solvers}_"
        self._solvers += 1
        return prefix

    def form(self, expr: ufl.Form) -> fem.Form:
        """Compile a form over the parent mesh with the bodies' entity maps."""
        return fem.form(expr, entity_maps=self.entity_maps)

    def assemble(self, compiled: fem.Form) -> float:
        """Assemble a compiled scalar form and sum over the ranks."""
        return self.comm.allreduce(fem.assemble_scalar(compiled), op=MPI.SUM)

    def assemble_many(self, compiled: Sequence[fem.Form | None]) -> np.ndarray:
        """Assemble compiled scalar forms (None: 0) and sum them over the ranks at once.

        The same numbers as :meth:`assemble` of each, with one reduction for all and
        dolfinx's C++ assembler called directly (per-step outputs).
        """
        return self.reduce(self.assemble_local(compiled))

    @staticmethod
    def assemble_local(compiled: Sequence[fem.Form | None]) -> np.ndarray:
        """Compiled scalar forms (None: 0), this rank's share: not summed over the ranks."""
        cpp = dolfinx.cpp.fem
        out = np.zeros(len(compiled))
        for k, c in enumerate(compiled):
            if c is not None:
                f = c._cpp_object
                out[k] = cpp.assemble_scalar(f, cpp.pack_constants(f), cpp.pack_coefficients(f))
        return out

    def reduce(self, local: np.ndarray) -> np.ndarray:
        """Sum an array of this rank's shares over the ranks (one reduction, in place)."""
        if self.comm.size > 1:
            self.comm.Allreduce(MPI.IN_PLACE, local, op=MPI.SUM)
        return local

    def bounding_box(self, body: int) -> tuple[np.ndarray, np.ndarray]:
        """A body's lowest and highest coordinates (m; collective)."""
        x = self.bodies[body].submesh.geometry.x[:, :self.gdim]
        lo, hi = x.min(axis=0, initial=np.inf), x.max(axis=0, initial=-np.inf)
        self.comm.Allreduce(MPI.IN_PLACE, lo, op=MPI.MIN)
        self.comm.Allreduce(MPI.IN_PLACE, hi, op=MPI.MAX)
        return lo, hi

    def weight(self) -> list[float]:
        """Weight |g| ∫ρ of each body (N, or N/m in plane strain)."""
        g = float(np.linalg.norm(self.gravity.value))
        return [self.assemble(self.form(g * b.ρ * b.dx)) for b in self.bodies]
