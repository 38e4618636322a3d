r"""The full-system Newton with an iterative linear solver (GMRES + GAMG) against MUMPS LU.

Run on purpose, never in CI (one rank; each solver in its own process, for its peak
memory)::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/iterative_full_system.py \
        --refinement 1 --steps 20 --solver lu   --out lu.json
    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/iterative_full_system.py \
        --refinement 1 --steps 20 --solver gamg --out gamg.json --compare lu.json

The ``goda3d`` case's reference stepper (``GN22(..., solver="reference")``: SNES on the
whole residual, the contact terms in its Jacobian) from its static state; its KSP is
either the reference's (``preonly`` + MUMPS LU) or GMRES (right-preconditioned, so that
its tolerance bounds the true residual) with :class:`TiedGAMG`:

- the interface's tangential unknowns are first rotated, pair by pair, into their mean
  and difference, ``(u_s ± u_m)/√2`` (an orthogonal T, so the system is T A T): the
  stuck friction's tangent ``μp/χ · β₁Δt`` couples each slave node to its master node
  with 10⁴–10⁶ times the bulk's diagonal (``[[K, −K], [−K, K]]``), which leaves the
  interface nodes without a strong connection inside their own body for GAMG's graph;
  after T it sits on the differences' diagonal alone (2K) and the means are bulk rows;
- GAMG on T A T with each body's six rigid modes (T-rotated) as its near-null space,
  the drop threshold 0.01 (measured: without T, or with GAMG's defaults, GMRES did not
  reach 1e-8 in 400 iterations; record 2026-11-29-iterative-full-system).

The interface here is ``goda3d``'s crest, normal to y: the tangential components are x
and z (checked). Printed and written (``--out``): per step the Newton and GMRES
iterations, CPU times (the step, the preconditioner's setups, the linear solves), the
caisson's and the mound's mean displacement; at the end the process's peak resident
memory (VmHWM). ``--compare`` prints the largest difference of the mean displacements
from another run's, relative to their largest value.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys
import tempfile
import time
from typing import Any

import numpy as np
from mpi4py import MPI

import breakwater  # noqa: F401  (loads the PETSc of the dolfinx wheel first)

# isort: split
from petsc4py import PETSc

from breakwater.casefile.case import load_case
from breakwater.model.layout import MonolithicLayout
from breakwater.statics.initial import initial_state
from breakwater.stepping.gn22 import GN22


def vm_hwm() -> float:
    """The process's peak resident memory (MB), from /proc/self/status."""
    for line in pathlib.Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return float(line.split()[1]) / 1024.0
    return float("nan")


def tie_transform(model: Any, components: tuple[int, ...]) -> tuple[PETSc.Mat, np.ndarray]:
    """T: the components of each coincident (caisson, mound) node pair into mean and difference.

    Returns:
        T (orthogonal and symmetric, serial) and the stacked dof coordinates.
    """
    layout = MonolithicLayout(model)
    n = int(layout.offsets[-1])
    x = np.zeros((n, 3))
    nodes: list[dict[tuple[float, ...], int]] = []
    for i, b in enumerate(model.bodies):
        xb = b.V.tabulate_dof_coordinates()[: b.V.dofmap.index_map.size_local]
        x[layout.offsets[i]:layout.offsets[i + 1]] = np.repeat(xb, 3, axis=0)
        nodes.append({tuple(np.round(p, 9)): layout.offsets[i] + 3 * k for k, p in enumerate(xb)})
    pairs = [(i, nodes[1][p]) for p, i in nodes[0].items() if p in nodes[1]]
    T = PETSc.Mat().createAIJ([n, n], nnz=2, comm=PETSc.COMM_SELF)
    T.setBlockSize(3)
    s = 1.0 / np.sqrt(2.0)
    done = np.zeros(n, bool)
    for p, q in pairs:
        for c in components:
            i, j = p + c, q + c
            T.setValues([i], [i, j], [s, s])
            T.setValues([j], [i, j], [s, -s])
            done[[i, j]] = True
    for i in np.flatnonzero(~done):
        T.setValue(i, i, 1.0)
    T.assemble()
    print(f"tie: {len(pairs)} node pairs, components {components}")
    return T, x


def rigid_modes(x: np.ndarray, body: np.ndarray) -> list[np.ndarray]:
    """Each body's six rigid modes on its own dofs (zero elsewhere)."""
    n = len(x)
    comp = np.tile(np.arange(3), n // 3)
    out = []
    for i in np.unique(body):
        mask = body == i
        d = x - x[mask].mean(axis=0)
        for j in range(6):
            w = np.zeros(n)
            if j < 3:
                w[comp == j] = 1.0
            else:
                a, b = [(1, 2), (2, 0), (0, 1)][j - 3]  # about axis j - 3
                w[comp == a] = -d[comp == a, b]
                w[comp == b] = d[comp == b, a]
            w[~mask] = 0.0
            out.append(w)
    return out


class TiedGAMG:
    """A PCSHELL: T GAMG(T A T)⁻¹ T, GAMG with the bodies' rigid modes (see the module)."""

    def __init__(self, T: PETSc.Mat, modes: list[np.ndarray], threshold: float) -> None:
        self.T, self.modes, self.threshold = T, modes, threshold
        self.At: PETSc.Mat | None = None
        self.inner = PETSc.KSP().create(PETSc.COMM_SELF)
        self.inner.setOptionsPrefix("tied_")
        opts = PETSc.Options()
        opts["tied_ksp_type"] = "preonly"
        opts["tied_pc_type"] = "gamg"
        opts["tied_pc_gamg_threshold"] = threshold
        self.inner.setFromOptions()
        self.w, self.z = T.createVecs()
        self.setup_cpu = 0.0

    def setUp(self, pc: PETSc.PC) -> None:
        """Rotate the Jacobian (T A T) and set GAMG up on it."""
        t0 = time.process_time()
        A = pc.getOperators()[0]
        if self.At is None:
            self.At = A.PtAP(self.T)
            vecs = []
            for m in self.modes:
                v, tv = self.T.createVecs()
                v.array[:] = m
                self.T.multTranspose(v, tv)
                vecs.append(tv)
            for i, v in enumerate(vecs):  # orthonormal (GAMG's QR wants independent ones)
                for u in vecs[:i]:
                    v.axpy(-v.dot(u), u)
                v.normalize()
            self.At.setNearNullSpace(PETSc.NullSpace().create(vectors=vecs))
        else:
            A.PtAP(self.T, result=self.At)
        self.inner.setOperators(self.At)
        self.inner.setUp()
        self.setup_cpu += time.process_time() - t0

    def apply(self, pc: PETSc.PC, x: PETSc.Vec, y: PETSc.Vec) -> None:
        """The preconditioned vector: y = T GAMG⁻¹ T x."""
        self.T.mult(x, self.w)
        self.inner.solve(self.w, self.z)
        self.T.mult(self.z, y)


def main() -> None:
    """Step goda3d with the chosen linear solver; print and write the measurements."""
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--refinement", type=float, default=1.0)
    p.add_argument("--steps", type=int, default=20)
    p.add_argument("--solver", choices=("lu", "gamg"), default="gamg")
    p.add_argument("--rtol", type=float, default=1e-10, help="GMRES's relative tolerance")
    p.add_argument("--threshold", type=float, default=0.01, help="GAMG's drop threshold")
    p.add_argument("--restart", type=int, default=100, help="GMRES's restart")
    p.add_argument("--out", type=pathlib.Path)
    p.add_argument("--compare", type=pathlib.Path)
    a = p.parse_args()
    if MPI.COMM_WORLD.size != 1:
        sys.exit("one rank only (the tie transform is built serially)")
    case = load_case("goda3d", [f"mesh.refinement={a.refinement}",
                                f"output.directory={tempfile.mkdtemp()}"])
    model, spec, _, _ = case.build(MPI.COMM_WORLD)
    model.set_time(0.0)
    init = initial_state(model)
    stepper = GN22(model, spec.dt, solver="reference")
    stepper.initialise(init.u, init.v)
    snes = stepper.solver.snes
    ksp = snes.getKSP()
    shell = None
    if a.solver == "gamg":
        normals = np.vstack([nd.normal for nd in stepper.nodes])
        assert np.allclose(np.abs(normals[:, 1]), 1.0), "the interface is not normal to y"
        T, x = tie_transform(model, (0, 2))
        layout = MonolithicLayout(model)
        body = np.repeat(np.arange(len(model.bodies)), np.diff(layout.offsets))
        shell = TiedGAMG(T, rigid_modes(x, body), a.threshold)
        ksp.setType("gmres")
        ksp.setGMRESRestart(a.restart)
        ksp.setPCSide(PETSc.PC.Side.RIGHT)
        ksp.setTolerances(rtol=a.rtol, atol=0.0, max_it=2000)
        pc = ksp.getPC()
        pc.setType("python")
        pc.setPythonContext(shell)
    n = stepper.solver.problem.A.getSize()[0]
    print(f"goda3d r{a.refinement}: {n} unknowns, solver {a.solver}, VmHWM after the static "
          f"state {vm_hwm():.0f} MB", flush=True)
    ksp_its = [0]
    ksp.setMonitor(lambda k, it, r: ksp_its.__setitem__(0, ksp_its[0] + (it > 0)))
    rows: list[dict[str, Any]] = []
    for step in range(a.steps):
        ksp_its[0] = 0
        setup0 = shell.setup_cpu if shell else 0.0
        t0 = time.process_time()
        stepper.stage()
        newton = stepper.solve()
        stepper.update()
        cpu = time.process_time() - t0
        means = [float(np.mean(u.x.array.reshape(-1, 3), axis=0)[0]) for u in stepper.u]
        rows.append({"step": step, "newton": newton, "ksp": ksp_its[0], "cpu": cpu,
                     "pc_setup_cpu": (shell.setup_cpu - setup0) if shell else None,
                     "mean_ux": means})
        print(f"step {step}: Newton {newton}, GMRES {ksp_its[0]}, CPU {cpu:.2f} s "
              f"({cpu / newton:.2f} s per Newton iteration), mean u_x {means}", flush=True)
    total_newton = sum(r["newton"] for r in rows)
    total_cpu = sum(r["cpu"] for r in rows)
    summary = {"refinement": a.refinement, "unknowns": n, "solver": a.solver,
               "rtol": a.rtol, "threshold": a.threshold, "steps": rows,
               "newton": total_newton, "ksp": sum(r["ksp"] for r in rows),
               "cpu": total_cpu, "cpu_per_newton": total_cpu / total_newton,
               "vm_hwm_mb": vm_hwm()}
    print(f"total: Newton {total_newton}, GMRES {summary['ksp']}, CPU {total_cpu:.1f} s, "
          f"{summary['cpu_per_newton']:.2f} s per Newton iteration, VmHWM "
          f"{summary['vm_hwm_mb']:.0f} MB")
    if a.out:
        a.out.write_text(json.dumps(summary, indent=1))
    if a.compare:
        other = json.loads(a.compare.read_text())
        m = min(len(rows), len(other["steps"]))
        mine = np.array([r["mean_ux"] for r in rows[:m]])
        theirs = np.array([r["mean_ux"] for r in other["steps"][:m]])
        rel = np.abs(mine - theirs).max(axis=0) / np.abs(theirs).max(axis=0)
        print(f"against {a.compare.name}: mean u_x of each body differs by at most {rel} "
              "of its largest value; Newton iterations per step "
              f"{[r['newton'] for r in rows[:m]]} against "
              f"{[r['newton'] for r in other['steps'][:m]]}")


if __name__ == "__main__":
    main()
