"""A contact model built from a gmsh mesh with named physical groups.

Bodies are named cell groups; each gets its own vector Lagrange space on a submesh, so
the displacement is discontinuous across the interfaces. Contact pairs are named facet
groups where a slave body meets a master body on a conforming interface; their terms
are interior-facet integrals on the parent mesh, with the slave always on the ``'+'``
side. All measures live on the parent mesh and the submeshes reach it through
``entity_maps``.

The bulk terms (M, C, K, loads) and the interface terms are separate forms
(:meth:`ContactModel.bulk_residual`, :meth:`ContactModel.interface_residual`), so
that a solver may factor the constant bulk operator once.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import dolfinx
import numpy as np
import ufl
from dolfinx import fem
from dolfinx.io import gmsh as gmshio
from mpi4py import MPI

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from breakwater.common.errors import MeshError
from breakwater.config.runspec import InitialSpec
from breakwater.contact.penetration import initial_overlap
from breakwater.contact.surfaces import SurfacePair, check_pair_settings
from breakwater.loads.fields import TractionField
from breakwater.model.mesh import group_tag


@dataclass(frozen=True)
class Material:
    """Linear isotropic elastic material.

    Give exactly one of ``shear_modulus`` or ``young_modulus``.

    Attributes:
        density: Mass density ρ (kg/m³).
        poisson: Poisson's ratio ν (-), in (-1, 1/2).
        shear_modulus: Shear modulus G (Pa).
        young_modulus: Young's modulus E (Pa).

    """

    density: float
    poisson: float
    shear_modulus: float | None = None
    young_modulus: float | None = None

    def __post_init__(self) -> None:
        if (self.shear_modulus is None) == (self.young_modulus is None):
            raise ValueError("give exactly one of shear_modulus and young_modulus")
        if not self.density > 0:
            raise ValueError(f"density must be > 0 (got {self.density})")
        if not -1.0 < self.poisson < 0.5:
            raise ValueError(f"poisson must be in (-1, 0.5) (got {self.poisson})")
        modulus = self.shear_modulus if self.young_modulus is None else self.young_modulus
        if not modulus > 0:  # type: ignore[operator]
            raise ValueError(f"elastic modulus must be > 0 (got {modulus})")

    @property
    def G(self) -> float:
        """Shear modulus (Pa)."""
        return self.lame[1]

    @property
    def E(self) -> float:
        """Young's modulus (Pa)."""
        return 2.0 * self.G * (1.0 + self.poisson)

    @property
    def lame(self) -> tuple[float, float]:
        """Lamé parameters (λ, μ) in Pa."""
        if self.shear_modulus is not None:
            return forms.lame_from_shear(self.shear_modulus, self.poisson)
        assert self.young_modulus is not None
        return forms.lame_from_young(self.young_modulus, self.poisson)

    @property
    def p_wave_speed(self) -> float:
        """Speed of dilatational waves, sqrt((λ + 2μ)/ρ) (m/s)."""
        λ, μ = self.lame
        return math.sqrt((λ + 2.0 * μ) / self.density)

    @property
    def constrained_modulus(self) -> float:
        """Oedometric modulus λ + 2μ (Pa): the 1D plane-strain bar modulus."""
        λ, μ = self.lame
        return λ + 2.0 * μ


@dataclass(frozen=True)
class Body:
    """A deformable body: a named cell group and its material."""

    name: str
    material: Material


@dataclass(frozen=True)
class ContactPair:
    """Penalty contact with regularised Coulomb friction on a named facet group.

    Attributes:
        interface: Facet group where the two bodies meet (conforming).
        slave: Body whose displacement is penalised against the master's.
        master: Body whose outward normal defines the gap.
        penalty: Normal penalty ε_n (N/m³).
        friction: Coulomb coefficient μ (-); 0 for frictionless contact.
        regularisation: Regularisation velocity χ (m/s).
        gap: Initial normal gap g_0 (m).

    The law itself is :class:`forms.ContactLaw` (in ``forms/contact.py``), built from
    these fields by :meth:`forms.ContactLaw.of`.
    """

    interface: str
    slave: str
    master: str
    penalty: float
    friction: float = 0.0
    regularisation: float = 1e-10
    gap: float = 0.0

    def __post_init__(self) -> None:
        check_pair_settings(self.penalty, self.friction, self.regularisation, self.slave,
                            self.master)


@dataclass(frozen=True)
class Fixed:
    """Zero displacement on a named facet group.

    Attributes:
        group: Facet group name.
        components: Displacement components fixed (0 = x, 1 = y, 2 = z); None for all.

    """

    group: str
    components: tuple[int, ...] | None = None


@dataclass(frozen=True)
class SurfaceLoad:
    """A traction ``amplitude(t) × field`` (Pa) on a named facet group.

    Attributes:
        group: Facet group on the boundary of one body (or an interface between two
            bodies, with ``body`` naming the side loaded).
        direction: Traction per unit amplitude (a vector of the geometric dimension);
            empty when ``field`` gives it.
        amplitude: Time function t ↦ scale factor.
        field: Traction per unit amplitude as a UFL expression of the position and the
            outward normal of the body (:mod:`breakwater.loads.fields`); None: the
            constant ``direction``.
        body: The body loaded; None: the one body whose boundary holds the group.
        name: The load of the case it comes from (the summary's applied loads).

    """

    group: str
    direction: tuple[float, ...]
    amplitude: Callable[[float], float]
    field: TractionField | None = None
    body: str | None = None
    name: str | None = None

    def unit_traction(self, x: ufl.core.expr.Expr, n: ufl.core.expr.Expr
                      ) -> ufl.core.expr.Expr:
        """The traction per unit amplitude at ``x`` (outward normal ``n``)."""
        if self.field is not None:
            return self.field.traction(x, n)
        return ufl.as_vector(self.direction)


@dataclass(frozen=True)
class Damping:
    """Rayleigh damping C = αM + βK (α in 1/s, β in s), the same for every body."""

    alpha: float = 0.0
    beta: float = 0.0


@dataclass
class _BodyData:
    """What the model builds for one body."""

    spec: Body
    index: int
    submesh: dolfinx.mesh.Mesh
    cell_map: dolfinx.mesh.EntityMap
    facet_tags: dolfinx.mesh.MeshTags
    V: fem.FunctionSpace
    dx: ufl.Measure
    ρ: fem.Constant
    λ: fem.Constant
    μ: fem.Constant


@dataclass
class _PairData:
    """What the model builds for one contact pair.

    Attributes:
        law: The contact law (:class:`forms.ContactLaw`) with ``fem.Constant``
            parameters; ``law.values()`` evaluates it on nodal arrays.

    """

    spec: ContactPair
    slave: int
    master: int
    facet_data: np.ndarray
    dS: ufl.Measure
    n: ufl.core.expr.Expr
    law: forms.ContactLaw

    @property
    def ε_n(self) -> fem.Constant:
        """The normal penalty (N/m³)."""
        return self.law.normal.ε_n


@dataclass
class _LoadData:
    """What the model builds for one load: ``traction = amplitude × unit``."""

    spec: SurfaceLoad
    body: int
    ds: ufl.Measure
    amplitude: fem.Constant
    unit: ufl.core.expr.Expr
    traction: ufl.core.expr.Expr = field(init=False)

    def __post_init__(self) -> None:
        self.traction = self.amplitude * self.unit


class ContactModel:
    """N deformable bodies in frictional contact, from a gmsh mesh with named groups.

    Args:
        mesh_data: dolfinx ``MeshData`` (see :func:`breakwater.model.mesh.read_mesh`), read
            with shared-facet ghosting.
        bodies: The bodies (named cell groups).
        pairs: The contact pairs (named facet groups).
        fixed: Dirichlet boundaries (named facet groups).
        loads: Time-dependent surface tractions.
        gravity: Body force per unit mass (m/s²), e.g. ``(0, -9.81)``.
        damping: Rayleigh damping.
        degree: Polynomial degree of the displacement (2: six-node triangles).
        surface_pairs: General contact pairs between two surfaces that need not match
            (:mod:`breakwater.contact.general`; the fast solver only).

    Attributes:
        initial: The initial state of a run (initial velocities, the loads of the
            static state; :mod:`breakwater.statics.initial`); set it before running.

    """

    def __init__(
        self,
        mesh_data: gmshio.MeshData,
        bodies: Sequence[Body],
        pairs: Sequence[ContactPair] = (),
        fixed: Sequence[Fixed] = (),
        loads: Sequence[SurfaceLoad] = (),
        gravity: Sequence[float] | None = None,
        damping: Damping | None = None,
        degree: int = 2,
        surface_pairs: Sequence[SurfacePair] = (),
    ) -> None:
        self.mesh_data = mesh_data
        self.mesh = msh = mesh_data.mesh
        self.comm: MPI.Comm = msh.comm
        tdim = msh.topology.dim
        self.gdim = msh.geometry.dim
        if mesh_data.cell_tags is None or mesh_data.facet_tags is None:
            raise MeshError("the mesh needs cell and facet physical groups")
        msh.topology.create_connectivity(tdim - 1, tdim)
        self._cell_body = np.full(msh.topology.index_map(tdim).size_local
                                  + msh.topology.index_map(tdim).num_ghosts, -1, np.int32)

        dx = ufl.Measure("dx", domain=msh, subdomain_data=mesh_data.cell_tags)
        self.bodies: list[_BodyData] = []
        for i, body in enumerate(bodies):
            tag = group_tag(mesh_data, body.name, tdim)
            cells = mesh_data.cell_tags.find(tag)
            ncells = self.comm.allreduce(len(cells))
            if ncells == 0:
                raise MeshError(f"body '{body.name}' has no cells")
            if np.any(self._cell_body[cells] >= 0):
                raise MeshError(f"body '{body.name}' overlaps another body")
            self._cell_body[cells] = i
            sub, cmap, vmap, _ = dolfinx.mesh.create_submesh(msh, tdim, cells)
            ftags = dolfinx.mesh.transfer_meshtags_to_submesh(mesh_data.facet_tags, sub, vmap,
                                                               cmap)
            sub.topology.create_connectivity(tdim - 1, tdim)
            V = fem.functionspace(sub, ("Lagrange", degree, (self.gdim,)))
            λ, μ = body.material.lame
            const = lambda v: fem.Constant(msh, dolfinx.default_scalar_type(v))  # noqa: E731
            self.bodies.append(_BodyData(body, i, sub, cmap, ftags, V, dx(tag),
                                         const(body.material.density), const(λ), const(μ)))
        self.entity_maps = [b.cell_map for b in self.bodies]
        self._by_name = {b.spec.name: b for b in self.bodies}

        self.W = ufl.MixedFunctionSpace(*(b.V for b in self.bodies))
        self.w = ufl.TestFunctions(self.W)
        self.gravity = fem.Constant(msh, np.array(gravity if gravity is not None
                                                  else np.zeros(self.gdim), dtype=float))
        d = damping or Damping()
        self.damping = d
        self.α = fem.Constant(msh, dolfinx.default_scalar_type(d.alpha))
        self.β = fem.Constant(msh, dolfinx.default_scalar_type(d.beta))

        # The integration data of every pair, in one list: dolfinx compiles a form only
        # if all its integrals of a type share one subdomain_data object.
        self._interface_data: list[tuple[int, np.ndarray]] = []
        self.pairs = [self._build_pair(k, p) for k, p in enumerate(pairs)]
        self.surface_pairs = [self._check_surfaces(p) for p in surface_pairs]
        self._fixed: list[tuple[str, int, tuple[int, ...]]] = []  # group, body, components
        self.bcs = [bc for f in fixed for bc in self._build_fixed(f)]
        self._load_data: list[tuple[int, np.ndarray]] = []
        self.loads = [self._build_load(k, ld) for k, ld in enumerate(loads)]
        self._solvers = 0  # solvers built on this model (see options_prefix)
        self.initial = InitialSpec()

    # --- set-up -------------------------------------------------------------------

    def body(self, name: str) -> _BodyData:
        """The data of a body by name."""
        try:
            return self._by_name[name]
        except KeyError:
            raise KeyError(f"no body named '{name}' (bodies: {', '.join(self._by_name)})") \
                from None

    def _build_pair(self, k: int, pair: ContactPair) -> _PairData:
        msh, data = self.mesh, self.mesh_data
        tdim = msh.topology.dim
        s, m = self.body(pair.slave).index, self.body(pair.master).index
        assert data.facet_tags is not None
        facets = data.facet_tags.find(group_tag(data, pair.interface, tdim - 1))
        integration = fem.compute_integration_domains(fem.IntegralType.interior_facet,
                                                      msh.topology, facets)
        if self.comm.allreduce(len(facets)) == 0 or \
                self.comm.allreduce(integration.size) == 0:
            raise MeshError(f"interface '{pair.interface}' has no facet shared by two cells "
                            "(is it a conforming interface between two bodies?)")
        # Reorder so that '+' is always the slave: unordered data gives wrong numbers.
        d = integration.reshape(-1, 4).copy()
        flip = self._cell_body[d[:, 0]] != s
        d[flip] = d[flip][:, [2, 3, 0, 1]]
        if not (np.all(self._cell_body[d[:, 0]] == s) and np.all(self._cell_body[d[:, 2]] == m)):
            raise MeshError(f"interface '{pair.interface}' does not lie between "
                            f"'{pair.slave}' and '{pair.master}'")
        # Nodal (Gauss-Lobatto) quadrature: the points are the facet's P2 nodes, i.e. the
        # paper's node-to-node contact; it also decouples the friction law node by node.
        tag = 1000 + k
        self._interface_data.append((tag, d.ravel()))
        dS = ufl.Measure("dS", domain=msh, subdomain_data=self._interface_data,
                         metadata={"quadrature_rule": "GLL", "quadrature_degree": 3})(tag)
        n = -ufl.FacetNormal(msh)("+")  # outward normal of the master ('-') side
        c = lambda v: fem.Constant(msh, dolfinx.default_scalar_type(v))  # noqa: E731
        return _PairData(pair, s, m, d, dS, n, forms.ContactLaw.of(pair, c))

    def _check_surfaces(self, pair: SurfacePair) -> SurfacePair:
        """A general pair whose surfaces lie on its bodies' boundaries.

        A surface group may lie on several bodies (a conforming interface shared by the
        two, or one group naming facets of both): each side of the pair takes the
        group's facets on its own body (:func:`breakwater.contact.surfaces.surface_dofs`).
        """
        for role, body, group in (("slave", pair.slave, pair.slave_surface),
                                  *(("master", pair.master, g) for g in pair.master_groups)):
            index = self.body(body).index
            counts = self._facet_counts(group)
            if counts[index] == 0:
                found = [b.spec.name for b, c in zip(self.bodies, counts, strict=True) if c]
                if not found:
                    raise MeshError(f"contact '{pair.name}': {role} surface '{group}' has "
                                    "no facet on any body")
                raise MeshError(f"contact '{pair.name}': {role} surface '{group}' lies on "
                                f"body '{', '.join(found)}', not on the {role} '{body}'")
        why = initial_overlap(self, pair)
        if why is not None:
            raise MeshError(why)
        return pair

    def surface_facets(self, body: str, groups: Sequence[str]) -> np.ndarray:
        """A body's facets (its submesh's, ghosts included) in any of several groups."""
        b, fdim = self.body(body), self.mesh.topology.dim - 1
        found = [b.facet_tags.find(group_tag(self.mesh_data, g, fdim)) for g in groups]
        return np.unique(np.concatenate(found)) if found else np.zeros(0, np.int32)

    def _facet_counts(self, group: str) -> list[int]:
        """The number of facets of a facet group on each body (every rank)."""
        tag = group_tag(self.mesh_data, group, self.mesh.topology.dim - 1)
        return [self.comm.allreduce(len(b.facet_tags.find(tag))) for b in self.bodies]

    def _locate(self, group: str) -> tuple[_BodyData, np.ndarray]:
        """The body whose boundary holds a facet group, and its facets in the submesh."""
        counts = self._facet_counts(group)
        owners = [i for i, c in enumerate(counts) if c > 0]
        if len(owners) != 1:
            raise MeshError(f"facet group '{group}' must lie on exactly one body "
                            f"(found on {len(owners)})")
        b = self.bodies[owners[0]]
        tag = group_tag(self.mesh_data, group, self.mesh.topology.dim - 1)
        return b, b.facet_tags.find(tag)

    def _build_fixed(self, fixed: Fixed) -> list[fem.DirichletBC]:
        body, facets = self._locate(fixed.group)
        fdim = self.mesh.topology.dim - 1
        comps = range(self.gdim) if fixed.components is None else fixed.components
        bcs = []
        for c in comps:
            if not 0 <= c < self.gdim:
                raise ValueError(f"fixed '{fixed.group}': component {c} out of range")
            Vc = body.V.sub(c)
            dofs = fem.locate_dofs_topological(Vc, fdim, facets)
            bcs.append(fem.dirichletbc(dolfinx.default_scalar_type(0.0), dofs, Vc))
        self._fixed.append((fixed.group, body.index, tuple(comps)))
        return bcs

    def fixed_on(self, body: str) -> list[tuple[str, tuple[int, ...]]]:
        """The fixed boundaries on a body: (facet group, displacement components held)."""
        index = self.body(body).index
        return [(group, comps) for group, i, comps in self._fixed if i == index]

    def _build_load(self, k: int, load: SurfaceLoad) -> _LoadData:
        """The load's measure: one-sided facet integrals on the loaded body.

        Every load integrates over the exterior-facet pairs (cell, local facet) of its
        body, in one shared list (dolfinx compiles a form only if all its integrals of
        a type share one subdomain_data object); on an interface between two bodies
        the pairs are those of the side named by ``load.body``.
        """
        msh, data = self.mesh, self.mesh_data
        fdim = msh.topology.dim - 1
        if load.field is None and len(load.direction) != self.gdim:
            raise ValueError(f"load on '{load.group}': direction needs {self.gdim} components")
        assert data.facet_tags is not None
        facets = data.facet_tags.find(group_tag(data, load.group, fdim))
        outer = np.intersect1d(facets, dolfinx.mesh.exterior_facet_indices(msh.topology))
        ext = fem.compute_integration_domains(fem.IntegralType.exterior_facet, msh.topology,
                                              outer).reshape(-1, 2)
        inner = np.setdiff1d(facets, outer)
        both = fem.compute_integration_domains(fem.IntegralType.interior_facet, msh.topology,
                                               inner).reshape(-1, 4)
        sides = np.vstack([ext, both[:, :2], both[:, 2:]])
        local = set(np.unique(self._cell_body[sides[:, 0]]).tolist()) if len(sides) else set()
        owners = sorted(set().union(*self.comm.allgather(local)))
        if load.body is not None:
            index = self.body(load.body).index
            if index not in owners:
                raise MeshError(f"facet group '{load.group}' is not on the boundary of "
                                f"body '{load.body}'")
        elif len(owners) != 1:
            names = ", ".join(self.bodies[i].spec.name for i in owners)
            raise MeshError(f"facet group '{load.group}' must lie on exactly one body "
                            f"(found on {len(owners)}{': ' + names if names else ''}; name "
                            "the body loaded)")
        else:
            index = owners[0]
        if self.comm.allreduce(len(inner)) == 0:
            entities = ext  # the exterior pairs in dolfinx's own order (as ds(tag) would)
        else:
            entities = sides[self._cell_body[sides[:, 0]] == index]
        tag = 2000 + k
        self._load_data.append((tag, entities.astype(np.int32).ravel()))
        ds = ufl.Measure("ds", domain=msh, subdomain_data=self._load_data)(tag)
        amp = fem.Constant(msh, dolfinx.default_scalar_type(load.amplitude(0.0)))
        unit = load.unit_traction(ufl.SpatialCoordinate(msh), ufl.FacetNormal(msh))
        return _LoadData(load, index, ds, amp, unit)

    # --- physics ------------------------------------------------------------------

    def set_time(self, t: float) -> None:
        """Evaluate the time-dependent loads at time ``t``."""
        for ld in self.loads:
            ld.amplitude.value = ld.spec.amplitude(t)

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

    def traction(self, pair: _PairData, u: Sequence, v: Sequence | None):
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

    def weight(self) -> list[float]:
        """Weight |g| ∫ρ of each body (N, or N/m in plane strain)."""
        g = float(np.linalg.norm(self.gravity.value))
        return [self.assemble(self.form(g * b.ρ * b.dx)) for b in self.bodies]
