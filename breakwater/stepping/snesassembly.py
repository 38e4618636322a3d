"""The SNES's residual and Jacobian: dolfinx's, less the work that is zero or constant.

:class:`~breakwater.stepping.solver.NewtonSolver` (the static states, the calibration,
the reference path's steps) hands PETSc's SNES these two callbacks in place of
:func:`dolfinx.fem.petsc.assemble_residual` and :func:`~dolfinx.fem.petsc.assemble_jacobian`:

- :class:`HomogeneousLifting`: the residual without the lifting of the Dirichlet
  conditions where that term is zero;
- :class:`ConstantBulk`: the Jacobian with its bulk part (the bodies' cell integrals,
  linear in the unknowns) assembled once per solve and the contact and load terms at
  every iteration.

Each is dolfinx's own assembly, in dolfinx's order, and falls back to it wherever its
condition does not hold.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI
from petsc4py import PETSc
from ufl.algorithms import expand_derivatives, extract_coefficients

__all__ = ["ConstantBulk", "HomogeneousLifting"]


def _zero_constant(bc: fem.DirichletBC) -> bool:
    """Whether a condition's value is a constant zero.

    A Function's value is not known to stay zero: False.
    """
    value = getattr(bc.g, "value", None)  # a Constant (Python or C++), else a Function
    return value is not None and not isinstance(bc.g, fem.Function) and \
        not np.asarray(value).any()


class HomogeneousLifting:
    """The SNES residual of a :class:`fem_petsc.NonlinearProblem`, its lifting skipped where zero.

    dolfinx's residual (:func:`dolfinx.fem.petsc.assemble_residual`) lifts the Dirichlet
    conditions at every evaluation: ``b −= J (g − x)`` on the columns of the constrained
    unknowns, an assembly of the Jacobian's element matrices on every cell that touches
    one. The model's conditions are homogeneous (``fixed`` groups: g = 0) and a Newton
    started from a state that satisfies them keeps it exactly (the constrained rows of
    the step are ``x − g``), so the lifted term is ``J · 0``: zero. It took a quarter of
    the 3D Goda case's static and calibration solves (its mound's cells all touch the
    flume's walls, 2026-11-27). Here the residual is assembled without it whenever every
    condition's value is zero and x vanishes at every constrained unknown (on every
    rank: one decision); otherwise dolfinx's residual, lifting included.

    Args:
        problem: The nonlinear problem whose residual this replaces.
        bcs: Its Dirichlet conditions.

    Attributes:
        lifted: Evaluations that needed the lifting.
        skipped: Evaluations without it.
    """

    def __init__(self, problem: fem_petsc.NonlinearProblem, bcs: Sequence[fem.DirichletBC]
                 ) -> None:
        self.problem, self.bcs = problem, list(bcs)
        self.lifted = self.skipped = 0
        b = problem.b
        self._blocks = b.getAttr("_blocks")
        forms = problem.F if isinstance(problem.F, Sequence) else [problem.F]
        self._bcs0 = fem.bcs_by_block(fem.extract_function_spaces(forms), self.bcs)
        self.homogeneous = all(_zero_constant(bc) for bc in self.bcs)
        # The constrained unknowns' owned entries: set_bc writes −(0 − 1) = 1 there.
        t, ones = b.duplicate(), b.duplicate()
        for v in (t, ones):
            v.setAttr("_blocks", self._blocks)
        t.set(0.0)
        ones.set(1.0)
        fem_petsc.set_bc(t, self._bcs0, x0=ones, alpha=-1.0)
        self._constrained = t.getArray(readonly=True) != 0.0
        t.destroy()
        ones.destroy()

    def lifting_is_zero(self, x: PETSc.Vec) -> bool:
        """Whether ``J (g − x)`` vanishes on the constrained columns (collective)."""
        zero = self.homogeneous and not x.getArray(readonly=True)[self._constrained].any()
        return bool(x.getComm().tompi4py().allreduce(zero, op=MPI.LAND))

    def __call__(self, snes: PETSc.SNES, x: PETSc.Vec, b: PETSc.Vec) -> None:
        """F(x) into b: :func:`dolfinx.fem.petsc.assemble_residual`, its lifting where nonzero."""
        p = self.problem
        if not self.lifting_is_zero(x):
            self.lifted += 1
            fem_petsc.assemble_residual(snes, x, b, p.u, p.F, p.J, self.bcs,
                                        _blocks=self._blocks)
            return
        self.skipped += 1
        # assemble_residual's steps, in its order, without apply_lifting.
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        fem_petsc.assign(x, p.u)
        if self._blocks is not None:
            b.setAttr("_blocks", self._blocks)
            x.setAttr("_blocks", self._blocks)
        with b.localForm() as local:
            local.set(0.0)
        fem_petsc.assemble_vector(b, p.F)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        fem_petsc.set_bc(b, self._bcs0, x0=x, alpha=-1.0)
        b.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)


class ConstantBulk:
    """The SNES Jacobian: its bulk part assembled once per solve, the rest at every iteration.

    The bodies' cell integrals (mass, damping, stiffness: linear elastodynamics) have a
    Jacobian that does not depend on the unknowns; dolfinx's Jacobian
    (:func:`dolfinx.fem.petsc.assemble_jacobian`) assembles them at every Newton
    iteration with the contact and load terms, and on the 3D Goda case they are 99 % of
    it (2.45 s of an assembly, the interface and load terms 0.03 s: 27-node hexahedra).
    Here they are assembled into a matrix of the Jacobian's pattern at the second
    iteration of each solve (their constants, G of a calibration or Δt of a step, may
    change between solves; a solve's first Jacobian is assembled whole, and a linear
    solve takes no other), copied into the Jacobian at each later iteration, and the
    other integrals added, with the Dirichlet rows and columns as dolfinx sets them. The sum
    is dolfinx's: the same kernels, each matrix entry summed in the same order (cells,
    then exterior and interior facets), bit for bit on one rank; on several, PETSc adds
    the contributions to other ranks' rows at the end of each assembly, so the entries
    on the ranks' boundary are summed in another order (round-off).

    Where the other integrals' values are those of the last iteration (assembled alone
    on their own pattern and compared exactly: a frictionless contact whose closed
    points stay, the iterations of a static solve after the first two or three), the
    Jacobian is the last one: it is left untouched, and PETSc keeps its LU factors
    (the factorisation is most of an iteration's cost: 19 of 20 s on ``goda3d`` at
    ``mesh.refinement = 2``). Newton's iterates are then the same bit for bit.

    Where the cell integrals' Jacobian depends on the unknowns, or splitting the forms
    would leave a block row or column without a form, dolfinx's Jacobian is used.

    Args:
        problem: The nonlinear problem (its matrix, unknowns and Jacobian form).
        F: The form whose derivative is the Jacobian (a rank-one form of the bodies' test
            functions).
        x: The unknowns, one Function per body.
        bcs: The Dirichlet conditions.
        entity_maps: The model's entity maps (the bodies' submeshes).
    """

    def __init__(self, problem: fem_petsc.NonlinearProblem, F: ufl.Form,
                 x: Sequence[fem.Function], bcs: Sequence[fem.DirichletBC],
                 entity_maps: Any) -> None:
        self.problem, self.bcs = problem, list(bcs)
        self._bulk: PETSc.Mat | None = None
        self._fresh = True  # the next Jacobian is a solve's first
        self._kept = False  # the kept matrix holds this solve's cell part
        cell = [i for i in F.integrals() if i.integral_type() == "cell"]
        rest = [i for i in F.integrals() if i.integral_type() != "cell"]
        self.split = bool(cell and rest)
        if self.split:
            a_cell, a_rest = (_jacobian_blocks(ufl.Form(its), x) for its in (cell, rest))
            unknowns = set(x)
            self.split = (_covers(a_cell) and _covers(a_rest) and not any(
                unknowns & set(extract_coefficients(b)) for row in a_cell for b in row
                if b is not None))
        if self.split:
            self.a_cell = fem.form(a_cell, entity_maps=entity_maps)
            self.a_rest = fem.form(a_rest, entity_maps=entity_maps)
            # The other integrals alone (their own small pattern): the last Jacobian's
            # values, to see whether it changes (_unchanged).
            self._rest = fem_petsc.create_matrix(self.a_rest, kind="mpi")
        self._rest_values: np.ndarray | None = None

    def new_solve(self) -> None:
        """A new solve starts: its first Jacobian is assembled whole, the cell part kept again."""
        self._fresh = True

    def destroy(self) -> None:
        """Free the bulk part's matrix and the other integrals'."""
        if self._bulk is not None:
            self._bulk.destroy()
            self._bulk = None
        if self.split:
            self._rest.destroy()

    def _unchanged(self) -> bool:
        """Whether the other integrals equal the last Jacobian's, exactly (collective).

        Their values at the current unknowns (assembled alone, without the Dirichlet
        conditions) compared with the last ones, which are replaced. Where they are
        equal, the Jacobian is the last one: the bulk part is the same within a solve.
        """
        R = self._rest
        R.zeroEntries()
        fem_petsc.assemble_matrix(R, self.a_rest)
        R.assemble()
        values = np.array(R.getValuesCSR()[2])
        last, self._rest_values = self._rest_values, values
        same = last is not None and np.array_equal(last, values)
        return bool(R.getComm().tompi4py().allreduce(same, op=MPI.LAND))

    def __call__(self, snes: PETSc.SNES, x: PETSc.Vec, J: PETSc.Mat, P: PETSc.Mat) -> None:
        """The Jacobian at x into J (P: the problem's preconditioner matrix, unused)."""
        p = self.problem
        if not self.split:
            fem_petsc.assemble_jacobian(snes, x, J, P, p.u, p.J, p.preconditioner, self.bcs)
            return
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        fem_petsc.assign(x, p.u)
        if self._fresh:
            # A solve's first Jacobian: assembled whole (a linear solve takes no other).
            # A second iteration keeps the cell part from then on (_keep). J's first
            # assembly also fixes its nonzero pattern, which the kept part's matrix
            # shares (PETSc drops the preallocated entries a final assembly leaves unused).
            self.assemble_whole(J)
            self._fresh, self._kept = False, False
            self._rest_values = None
            self._unchanged()  # the other integrals' values now, for the next iteration
            return
        if self._unchanged():
            # The same Jacobian (a frictionless contact whose closed points stay): J left
            # as it is keeps its LU factors (PETSc's PCSetUp sees an unchanged matrix).
            return
        if not self._kept:
            self._keep(J)
        assert self._bulk is not None
        self._bulk.copy(J, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)  # type: ignore[arg-type]
        fem_petsc.assemble_matrix(J, self.a_rest, self.bcs, diag=1.0)
        J.assemble()

    def assemble_whole(self, J: PETSc.Mat) -> None:
        """The Jacobian at the problem's current unknowns into J, each entry as dolfinx sums it.

        The cell part, then the other integrals, with the Dirichlet rows and columns.
        """
        J.zeroEntries()
        if not self.split:
            fem_petsc.assemble_matrix(J, self.problem.J, self.bcs, diag=1.0)
            J.assemble()
            return
        fem_petsc.assemble_matrix(J, self.a_cell, self.bcs, diag=1.0)
        J.assemble(PETSc.Mat.AssemblyType.FLUSH)  # the diagonal was set: now adds
        fem_petsc.assemble_matrix(J, self.a_rest, self.bcs, diag=1.0)
        J.assemble()

    def _keep(self, J: PETSc.Mat) -> None:
        """Assemble the cell part into the kept matrix (J's pattern and local numbering)."""
        if self._bulk is None:
            self._bulk = J.duplicate()
            self._bulk.setLGMap(*J.getLGMap())
        self._bulk.zeroEntries()
        fem_petsc.assemble_matrix(self._bulk, self.a_cell, self.bcs, diag=1.0)
        self._bulk.assemble()
        self._kept = True


def _jacobian_blocks(F: ufl.Form, x: Sequence[fem.Function]) -> list[list[ufl.Form | None]]:
    """The block Jacobian of F, its derivatives expanded, zero blocks None."""
    blocks = fem_petsc.derivative_block(ufl.extract_blocks(F), list(x))
    out: list[list[ufl.Form | None]] = []
    for row in blocks:
        out.append([])
        for b in row:
            b = None if b is None else expand_derivatives(b)
            out[-1].append(None if b is None or b.empty() else b)
    return out


def _covers(a: list[list[ufl.Form | None]]) -> bool:
    """Whether every block row and column has a form (dolfinx's blocked assembly needs it)."""
    return all(any(b is not None for b in row) for row in a) and all(
        any(row[j] is not None for row in a) for j in range(len(a[0])))
