"""The energy ledger's bulk terms, from UFL forms or from the fast solver's cached M and K.

Each step the ledger (:class:`~breakwater.energy.ledger.EnergyLedger`) needs five terms over
the whole mesh, in the order of :data:`TERMS` (this rank's share of each: the ledger sums
them over the ranks with its interface entries in one reduction):

- the kinetic energy ½ v₁·Mv₁ = ½∫ρv·v and the strain energy ½ u₁·Ku₁ = ½∫σ:ε;
- the Rayleigh power v̄·Cv̄ = α v̄·Mv̄ + β v̄·Kv̄ = ∫αρv̄·v̄ + βσ(v̄):ε(v̄), v̄ = ½(v₀ + v₁);
- the external work f_g·Δu + Σ_k ½(A_k(t₀) + A_k(t₁)) f_k·Δu = ∫ρb·Δu + ∫½(t₀ + t₁)·Δu,
  with f_g gravity's load vector and f_k load k's at unit amplitude A_k = 1;
- the bulk share of the numerical dissipation (:mod:`breakwater.energy.dissipation`).

Two sources give the same numbers (to round-off: the same quadratic forms, the same
quadrature, summed in another order):

- :class:`FormTerms`: UFL scalar forms assembled over the whole mesh (the reference
  solver, which caches no matrix);
- :class:`MatrixTerms`: the fast solver's M, K and load vectors
  (:class:`~breakwater.stepping.bulk.BulkOperators`, assembled once). Per step two sparse
  products, each a batch of columns in one pass over the matrix (``MatMatMult`` with a
  dense block): M [v₁, v̄, Δa] and K [u₁, v̄], then dot products of owned entries. Where
  M and K share their pattern (always; on any number of ranks), from the state's
  products [Mv, Ma, Ku, Kv, Ka] (:mod:`breakwater.stepping.stateproducts`: one compiled
  pass over the matrices' CSR arrays per accepted step, which the next step's predictor
  uses too) and the start state's, kept from the last record (:func:`ledger_sums`:
  Mv̄ = ½(Mv₀ + Mv₁), ...; no pass of its own), equal to the MatMatMult products to
  round-off; where the start state is not the last record's, the MatMatMult products.
  BulkOperators assembles M and K without the Dirichlet conditions (only the step
  matrix A has its fixed rows and columns replaced), so their quadratic forms are the
  integrals above; the fixed DOFs are zero anyway.

:func:`bulk_terms` picks the source.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np
from dolfinx import fem
from petsc4py import PETSc

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms: forms/
from breakwater.common.arrays import equal
from breakwater.common.jit import kernel
from breakwater.energy import dissipation as numerical
from breakwater.model.parts import StageWatch
from breakwater.stepping.gn22 import GN22
from breakwater.stepping.stateproducts import StateProducts

__all__ = ["SOURCES", "TERMS", "BulkTerms", "FormTerms", "MatrixTerms", "bulk_terms",
           "ledger_sums"]

#: The bulk terms, in the order of :meth:`BulkTerms.local`.
TERMS = ("kinetic", "strain", "rayleigh_power", "external_work", "numerical_dissipation")
#: The sources of :func:`bulk_terms` (``auto``: ``matrices`` on the fast solver).
SOURCES = ("auto", "forms", "matrices")


class BulkTerms(Protocol):
    """The bulk terms of the stepper's current state, this rank's share."""

    def local(self, step: bool) -> np.ndarray:
        """The :data:`TERMS`, shape (5,); with ``step`` False the last three are 0.

        Args:
            step: The state is the end of a step (from the ledger's ``u0``, ``v0``, the
                start amplitudes and the stepper's Δa, Δt), not the first record.
        """
        ...

    def sync(self) -> None:
        """Take the staged loads' current stage as the start of the next step (resume)."""
        ...

    def destroy(self) -> None:
        """Free the PETSc objects it holds (collective)."""
        ...


class FormTerms:
    """The bulk terms as UFL scalar forms over the bodies.

    Args:
        stepper: The stepper.
        u0: Displacements at the start of the step (the ledger's copies).
        v0: Velocities at the start of the step.
        amp0: The loads' amplitudes at the start of the step (the ledger's).
    """

    def __init__(self, stepper: GN22, u0: Sequence[fem.Function], v0: Sequence[fem.Function],
                 amp0: Sequence[fem.Constant]) -> None:
        s, m = stepper, stepper.model
        self.model = m
        bodies = list(enumerate(m.bodies))
        v̄ = [0.5 * (a + b) for a, b in zip(s.v, v0, strict=True)]
        Δu = [a - b for a, b in zip(s.u, u0, strict=True)]
        self._stored = [
            m.form(sum(forms.kinetic_energy(b.ρ, s.v[i], b.dx) for i, b in bodies)),
            m.form(sum(forms.strain_energy(s.u[i], b.λ, b.μ, b.dx) for i, b in bodies))]
        rayleigh = m.form(sum(forms.rayleigh_power(m.α, m.β, b.ρ, v̄[i], b.λ, b.μ, b.dx)
                              for i, b in bodies))
        work = sum(forms.external_power(b.ρ, m.gravity, Δu[i], b.dx) for i, b in bodies)
        # A staged field's traction at the start of the step reads the parameters it
        # had there: copies, set after each record.
        self._parameters: list[tuple[fem.Constant, fem.Constant]] = []
        for ld, a0 in zip(m.loads, amp0, strict=True):
            if ld.parameters is not None and ld.unit_with is not None:
                c0 = fem.Constant(m.mesh, np.array(ld.parameters.value))
                self._parameters.append((c0, ld.parameters))
                t̄ = 0.5 * (a0 * ld.unit_with(c0) + ld.amplitude * ld.unit)
            else:
                t̄ = 0.5 * (a0 + ld.amplitude) * ld.unit
            work += forms.surface_traction(t̄, Δu[ld.body], ld.ds)
        self._step = [rayleigh, m.form(work), numerical.bulk_form(s)]

    def local(self, step: bool) -> np.ndarray:
        """The :data:`TERMS` (see :meth:`BulkTerms.local`)."""
        if step:
            out = self.model.assemble_local([*self._stored, *self._step])
        else:
            out = np.concatenate([self.model.assemble_local(self._stored), np.zeros(3)])
        self.sync()
        return out

    def sync(self) -> None:
        """The start parameters of the staged loads set to their current ones."""
        for c0, c in self._parameters:
            c0.value[:] = c.value

    def destroy(self) -> None:
        """Nothing to free (the forms hold no PETSc object)."""


@kernel
def ledger_sums(x: np.ndarray, P1: np.ndarray, P0: np.ndarray, loads: np.ndarray,
                amplitudes: np.ndarray, k2: float, k3: float, step: bool) -> np.ndarray:
    """The dot products of the bulk terms, from the products of the end and start states.

    ``[v·Mv, u·Ku, v̄·Mv̄, v̄·Kv̄, f·Δu, Δa·Mv̄, (MΔa)·(k₂a + k₃Δa), Δa·Kv̄]`` (with ``step``
    False only the first two; the rest 0), v̄ = ½(v₀ + v₁), Δu = u₁ − u₀, f = Σ_l
    amplitudes_l loads[:, l]. With P₁ = [Mv₁, Ma₁, Ku₁, Kv₁, Ka₁]
    (:mod:`breakwater.stepping.stateproducts`) and P₀ = [Mv₀, Ma₀, Kv₀]:
    Mv̄ = ½(Mv₀ + Mv₁), Kv̄ = ½(Kv₀ + Kv₁), MΔa = Ma₁ − Ma₀; no pass over the matrices
    (equal to the products of the combined vectors to round-off).

    Args:
        x: Rows u₁, u₀, v₁, v₀, a₁, Δa (owned entries), shape (6, n).
        P1: The end state's products, shape (5, n).
        P0: The start state's Mv, Ma, Kv, shape (3, n) (unread with ``step`` False).
        loads: The load vectors at unit amplitude, shape (n, loads).
        amplitudes: Their amplitudes over the step.
        k2: The coefficient of a₁·MΔa.
        k3: The coefficient of Δa·MΔa.
        step: The state is the end of a step (else the first record: two sums only).
    """
    u, u0, v, v0, a, da = x[0], x[1], x[2], x[3], x[4], x[5]
    out = np.zeros(8)
    for i in range(u.shape[0]):
        out[0] += v[i] * P1[0, i]
        out[1] += u[i] * P1[2, i]
    if not step:
        return out
    for i in range(u.shape[0]):
        vb = (v0[i] + v[i]) * 0.5
        mvb = (P0[0, i] + P1[0, i]) * 0.5
        kvb = (P0[2, i] + P1[3, i]) * 0.5
        mda = P1[1, i] - P0[1, i]
        f = 0.0
        for q in range(amplitudes.shape[0]):
            f += loads[i, q] * amplitudes[q]
        out[2] += vb * mvb
        out[3] += vb * kvb
        out[4] += f * (u[i] - u0[i])
        out[5] += da[i] * mvb
        out[6] += mda * (k2 * a[i] + k3 * da[i])
        out[7] += da[i] * kvb
    return out


class StateSums:
    """:class:`MatrixTerms`' sums from the state's products (this rank's share).

    The end state's products P₁ (:class:`~breakwater.stepping.stateproducts.StateProducts`,
    formed once per accepted step, the next step's predictor uses them too) and the start
    state's Mv, Ma, Kv kept from the last record give :func:`ledger_sums`; where the start
    state is not the last record's (a step taken without a record), none
    (:meth:`MatrixTerms.local` takes the MatMatMult products then).

    Args:
        products: The bulk's state products (on: one sparsity pattern).
        rows: The Functions (one per body) of u₁, u₀, v₁, v₀, a₁ and Δa.
        offsets: The bodies' ranges in the stacked vector.
        loads: The load vectors' columns (n, loads) (the caller's, refreshed in place).
    """

    def __init__(self, products: StateProducts, rows: Sequence[Sequence[fem.Function]],
                 offsets: np.ndarray, loads: np.ndarray) -> None:
        self.products, self.offsets, self.loads = products, offsets, loads
        n = int(offsets[-1])
        self.x = np.zeros((6, n))
        # Views of the Functions' owned entries (their storage does not move).
        self._views = [(self.x[k], [f.x.array[:n_b] for f, n_b in
                                    zip(fns, np.diff(offsets), strict=True)])
                       for k, fns in enumerate(rows)]
        # The start state: its (u, v) and Mv, Ma, Kv.
        self._start = (np.full(n, np.nan), np.full(n, np.nan), np.zeros((3, n)))
        ones = np.ones(loads.shape[1])  # compiled (or loaded from numba's cache) now
        ledger_sums(self.x, np.zeros((5, n)), self._start[2], loads, ones, 0.0, 0.0, True)

    def _fill(self) -> None:
        """The rows of x from the Functions."""
        for row, arrays in self._views:
            for lo, hi, array in zip(self.offsets[:-1], self.offsets[1:], arrays, strict=True):
                row[lo:hi] = array

    def _keep(self, P: np.ndarray) -> None:
        """The state (u₁, v₁) of x and its Mv, Ma, Kv: the next step's start."""
        u, v, P0 = self._start
        u[:], v[:] = self.x[0], self.x[2]
        P0[0], P0[1], P0[2] = P[0], P[1], P[3]

    def restart(self) -> None:
        """The current state's products kept as the next step's start (a resume).

        A resumed run's are the uninterrupted run's numbers: one kernel, one state.
        """
        self._fill()
        x = self.x
        self._keep(self.products.of(x[0], x[2], x[4]))

    def sums(self, step: bool, amplitudes: np.ndarray, k2: float, k3: float
             ) -> np.ndarray | None:
        """:func:`ledger_sums` for the Functions' state now (None: the start unknown)."""
        self._fill()
        x = self.x
        P1 = self.products.of(x[0], x[2], x[4])
        u0, v0, P0 = self._start
        known = self.products.all(not step or (equal(u0, x[1]) and equal(v0, x[3])))
        out = ledger_sums(x, P1, P0, self.loads, amplitudes, k2, k3, step) if known else None
        self._keep(P1)
        return out


class MatrixTerms:
    """The bulk terms from the fast solver's cached M, K and load vectors.

    Args:
        stepper: The stepper, on the fast solver
            (:class:`~breakwater.stepping.condensed.CondensedNewton`).
        u0: Displacements at the start of the step (the ledger's copies).
        v0: Velocities at the start of the step.
        amp0: The loads' amplitudes at the start of the step (the ledger's).
    """

    def __init__(self, stepper: GN22, u0: Sequence[fem.Function], v0: Sequence[fem.Function],
                 amp0: Sequence[fem.Constant]) -> None:
        solver = stepper.fast
        if solver is None:
            raise ValueError("the ledger's bulk terms from matrices need the fast solver "
                             "(time.solver = \"fast\")")
        self.stepper, self.u0, self.v0, self.amp0 = stepper, u0, v0, amp0
        m = stepper.model
        self.bulk = bulk = solver.bulk
        self.layout = solver.layout
        self.alpha, self.beta = m.damping.alpha, m.damping.beta
        self.beta1, self.beta2 = stepper.params.beta1, stepper.params.beta2
        numerical_on = not self.beta1 == self.beta2 == 0.5
        # The columns each matrix multiplies (only those some term needs), by name.
        self._columns = {
            "M": {c: k for k, c in enumerate(
                ["v", *(["v̄"] if self.alpha or numerical_on else []),
                 *(["Δa"] if numerical_on else [])])},
            "K": {c: k for k, c in enumerate(["u", *(["v̄"] if self.beta else [])])}}
        n = int(self.layout.offsets[-1])
        self._in: dict[str, PETSc.Mat] = {}
        self._out: dict[str, PETSc.Mat] = {}
        for name, A in (("M", bulk.M), ("K", bulk.K)):
            X = PETSc.Mat().createDense(((n, None), (None, len(self._columns[name]))),
                                        comm=m.comm)  # type: ignore[arg-type]
            X.setUp()
            X.assemble()
            self._in[name], self._out[name] = X, A.matMult(X)
        # The load vectors' owned entries, one column each (gravity's first, amplitude 1),
        # and the loads' amplitude Constants (the model's, at the end of the step).
        loads = bulk.load_vectors
        self._amplitudes: list[fem.Constant] = []
        for a, _ in loads[1:]:
            assert a is not None
            self._amplitudes.append(a)
        self._loads = np.column_stack([np.array(vec.array[:n]) for _, vec in loads])
        # The loads whose field changes at given times: their columns taken again when
        # their stage changes.
        self._watch = StageWatch(m.loads)
        # The sums from the state's products (else PETSc's products).
        self._sums = StateSums(bulk.products, (stepper.u, u0, stepper.v, v0, stepper.a,
                                               stepper.da), self.layout.offsets,
                               self._loads) if bulk.products.on else None

    def _owned(self, functions: Sequence[fem.Function]) -> np.ndarray:
        """The owned entries of one Function per body, stacked."""
        return self.layout.fill(functions, np.empty(int(self.layout.offsets[-1])))

    def _products(self) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray],
                                 dict[str, np.ndarray]]:
        """The vectors (owned entries) and their products with M and K, by name.

        Each matrix multiplies its columns (the vectors written into its dense input
        block) in one pass (``MatMatMult``).
        """
        s = self.stepper
        X = {k: self._in[k].getDenseArray() for k in ("M", "K")}
        cm, ck = self._columns["M"], self._columns["K"]
        x = {"v": self.layout.fill(s.v, X["M"][:, cm["v"]]),
             "u": self.layout.fill(s.u, X["K"][:, ck["u"]])}
        if "v̄" in cm or "v̄" in ck:
            x["v̄"] = v̄ = self._owned(self.v0)
            v̄ += x["v"]
            v̄ *= 0.5
            for name, cols in (("M", cm), ("K", ck)):
                if "v̄" in cols:
                    X[name][:, cols["v̄"]] = v̄
        if "Δa" in cm:
            x["Δa"] = self.layout.fill(s.da, X["M"][:, cm["Δa"]])
        products = []
        for name, A in (("M", self.bulk.M), ("K", self.bulk.K)):
            A.matMult(self._in[name], self._out[name])
            y = self._out[name].getDenseArray(readonly=True)
            products.append({c: y[:, k] for c, k in self._columns[name].items()})
        return x, products[0], products[1]

    def _amplitudes_over_step(self) -> np.ndarray:
        """Gravity's 1, then each load's mean amplitude over the step."""
        return np.array([1.0, *(0.5 * (float(a0.value) + float(a1.value))
                                for a0, a1 in zip(self.amp0, self._amplitudes, strict=True))])

    def local(self, step: bool) -> np.ndarray:
        """The :data:`TERMS` (see :meth:`BulkTerms.local`).

        A staged load whose field changed in the step did work ½(A₀ f₀ + A₁ f₁)·Δu (f₀
        its start vector): the sums take ½(A₀ + A₁) f₁·Δu; ½A₀ (f₀ − f₁)·Δu is added.
        """
        old = self._refresh()
        out = self._local_sums(step) if self._sums is not None else self.local_products(step)
        if step and old:
            n = int(self.layout.offsets[-1])
            du = self._owned(self.stepper.u) - self._owned(self.u0)
            for k, f0 in old.items():
                a0 = float(self.amp0[k].value)
                out[3] += 0.5 * a0 * _dot(f0 - self._loads[:n, k + 1], du)
        return out

    def sync(self) -> None:
        """The staged loads' columns taken at their current stage, without correction.

        The state's products kept as the next step's start
        (:meth:`StateSums.restart`).
        """
        self._refresh()
        if self._sums is not None:
            self._sums.restart()

    def _refresh(self) -> dict[int, np.ndarray]:
        """Take the staged loads' vectors at their current stage; the columns replaced."""
        if not self._watch:
            return {}
        loads, n = self.bulk.load_vectors, int(self.layout.offsets[-1])
        old = {}
        for k in self._watch.changed():
            old[k] = self._loads[:, k + 1].copy()
            self._loads[:, k + 1] = loads[k + 1][1].array[:n]
        return old

    def _local_sums(self, step: bool) -> np.ndarray:
        """:meth:`local` from the state's products: :meth:`StateSums.sums`."""
        s = self.stepper
        assert self._sums is not None
        numerical_on = "Δa" in self._columns["M"]
        k1, k2, k3, k4 = numerical.bulk_coefficients(
            float(s.dt.value), self.beta1, self.beta2, self.alpha, self.beta) \
            if step and numerical_on else (0.0, 0.0, 0.0, 0.0)
        sums = self._sums.sums(step, self._amplitudes_over_step() if step else np.ones(0),
                               k2, k3)
        if sums is None:
            return self.local_products(step)
        out = np.zeros(len(TERMS))
        out[0] = 0.5 * sums[0]
        out[1] = 0.5 * sums[1]
        if not step:
            return out
        if self.alpha:
            out[2] += self.alpha * sums[2]
        if self.beta:
            out[2] += self.beta * sums[3]
        out[3] = sums[4]
        if numerical_on:
            out[4] = k1 * sums[5] + sums[6]
            if self.beta:
                out[4] += k4 * sums[7]
        return out

    def local_products(self, step: bool) -> np.ndarray:
        """:meth:`local` from ``MatMatMult`` products and NumPy dot products."""
        s = self.stepper
        x, Mx, Kx = self._products()
        u, v = x["u"], x["v"]
        out = np.zeros(len(TERMS))
        out[0] = 0.5 * _dot(v, Mx["v"])
        out[1] = 0.5 * _dot(u, Kx["u"])
        if not step:
            return out
        if self.alpha:
            out[2] += self.alpha * _dot(x["v̄"], Mx["v̄"])
        if self.beta:
            out[2] += self.beta * _dot(x["v̄"], Kx["v̄"])
        amplitudes = self._amplitudes_over_step()
        out[3] = _dot(np.einsum("ij,j->i", self._loads, amplitudes), u - self._owned(self.u0))
        if "Δa" in Mx:
            Δa = x["Δa"]
            k1, k2, k3, k4 = numerical.bulk_coefficients(float(s.dt.value), self.beta1,
                                                         self.beta2, self.alpha, self.beta)
            out[4] = k1 * _dot(Δa, Mx["v̄"]) + _dot(Mx["Δa"], k2 * self._owned(s.a) + k3 * Δa)
            if self.beta:
                out[4] += k4 * _dot(Δa, Kx["v̄"])
        return out

    def destroy(self) -> None:
        """Free the PETSc objects."""
        for X in (*self._in.values(), *self._out.values()):
            X.destroy()


def _dot(x: np.ndarray, y: np.ndarray) -> float:
    """x·y without BLAS.

    NumPy's OpenBLAS splits a dot product of more than 10,000 entries over its threads
    (two here); on a shared machine waiting for the second thread to be scheduled made
    the ledger's products take 20 ms a step at refinement 3 (0.02 ms single-threaded).
    """
    return float(np.einsum("i,i->", x, y))


def bulk_terms(stepper: GN22, u0: Sequence[fem.Function], v0: Sequence[fem.Function],
               amp0: Sequence[fem.Constant], source: str = "auto") -> FormTerms | MatrixTerms:
    """The ledger's bulk terms from the given source (see :data:`SOURCES`).

    ``auto``: the cached matrices on the fast solver, the forms on the reference solver.
    """
    if source not in SOURCES:
        raise ValueError(f"source must be one of {', '.join(SOURCES)} (got {source!r})")
    if source == "auto":
        source = "matrices" if stepper.fast is not None else "forms"
    return (MatrixTerms if source == "matrices" else FormTerms)(stepper, u0, v0, amp0)
