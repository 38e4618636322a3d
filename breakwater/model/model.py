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

The model's parts: the settings (:mod:`~breakwater.model.parts`,
:mod:`~breakwater.model.pairs`), the named groups on the bodies, fixed boundaries and
loads (:mod:`~breakwater.model.groups`), the forms and assembly helpers
(:mod:`~breakwater.model.residual`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import dolfinx
import numpy as np
import ufl
from dolfinx import fem
from dolfinx.io import gmsh as gmshio

if TYPE_CHECKING:
    from mpi4py import MPI

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from breakwater.common import formcache, petscfree
from breakwater.common.errors import CaseError, MeshError
from breakwater.config.runspec import InitialSpec
from breakwater.model.built import KnownAttributes, built_parts, gravity_value, initial_setting
from breakwater.model.groups import ModelGroups
from breakwater.model.mesh import facet_type, group_tag
from breakwater.model.pairs import HEXAHEDRA, ContactPair, PairData, SurfacePair, three_d_general
from breakwater.model.parts import (
    Body,
    BodyData,
    Damping,
    Fixed,
    LoadData,
    Material,
    SurfaceLoad,
)

formcache.install()  # the forms' compilations, interrupted, leave the JIT cache usable
petscfree.install()  # dolfinx's destructors leave PETSc objects for a collective release

__all__ = ["Body", "BodyData", "ContactModel", "ContactPair", "Damping", "Fixed", "LoadData",
           "Material", "PairData", "SurfaceLoad", "SurfacePair"]


def interface_quadrature(msh: dolfinx.mesh.Mesh, degree: int = 2) -> dict[str, Any]:
    """The quadrature of the conforming pairs' interface integrals, by facet shape.

    Its points are always the facet's nodes: the paper's node-to-node contact, which
    also decouples the friction law node by node (Newton's slip guard acts on nodes; at
    Gauss points between nodes the regularised law, χ = 1e-10 m/s, makes Newton cycle).

    - Intervals (2D) and quadrilaterals (hexahedra): Gauss–Lobatto of degree 3 (the P2
      facet's nodes); linear hexahedra's quadrilaterals: of degree 1 (their vertices).
    - Triangles of linear tetrahedra (``degree`` 1): the vertex rule, A/3 at each vertex
      (exact for the P1 fields, and the consistent split of a uniform pressure).
      Quadratic tetrahedra are refused by :class:`ContactModel`: no nodal rule with
      positive weights integrates a six-node triangle's quadratics (the exact one gives
      its vertices weight 0, the consistent share of a uniform pressure), so their nodal
      pressures would alternate between vertices and mid-edge nodes.

    Raises:
        ValueError: Quadratic triangular facets.
    """
    facet = facet_type(msh)
    if facet == dolfinx.mesh.CellType.triangle:
        if degree != 1:
            raise ValueError("quadratic tetrahedra")
        points = np.array([[0, 0], [1, 0], [0, 1]], float)
        weights = np.full(3, 1 / 6)  # reference triangle: area 1/2
        return {"quadrature_rule": "custom", "quadrature_points": points,
                "quadrature_weights": weights, "quadrature_degree": 1}
    if facet == dolfinx.mesh.CellType.quadrilateral and degree == 1:
        return {"quadrature_rule": "GLL", "quadrature_degree": 1}  # the 4 vertices
    return {"quadrature_rule": "GLL", "quadrature_degree": 3}


class ContactModel(KnownAttributes, ModelGroups):
    """N deformable bodies in frictional contact, from a gmsh mesh with named groups.

    Args:
        mesh_data: dolfinx ``MeshData`` (see :func:`breakwater.model.mesh.read_mesh`), read
            with shared-facet ghosting.
        bodies: The bodies (named cell groups).
        pairs: The contact pairs (named facet groups).
        fixed: Dirichlet boundaries (named facet or point groups).
        loads: Time-dependent surface tractions.
        gravity: Body force per unit mass (m/s²), e.g. ``(0, -9.81)``.
        damping: Rayleigh damping.
        degree: Polynomial degree of the displacement (2: six-node triangles).
        surface_pairs: General contact pairs between two surfaces that need not match
            (:mod:`breakwater.contact.general`; the fast solver only).

    Attributes:
        initial: The initial state of a run (:mod:`breakwater.statics.initial`), set
            before running and checked then (:func:`~breakwater.model.built.check_initial`).
        bodies, pairs, surface_pairs, loads: What was built of each (tuples; their
            settings fixed, unknown attributes refused: :mod:`breakwater.model.built`).
    """

    bodies = built_parts[BodyData]()
    pairs = built_parts[PairData]()
    surface_pairs = built_parts[SurfacePair]()
    loads = built_parts[LoadData]()
    initial = initial_setting()

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
        _pair_names_once(pairs, surface_pairs)
        self.mesh_data = mesh_data
        self.mesh = msh = _finite(mesh_data.mesh)
        self.comm = msh.comm
        tdim = msh.topology.dim
        self.gdim = msh.geometry.dim
        self.degree = degree
        if mesh_data.cell_tags is None or mesh_data.facet_tags is None:
            raise MeshError("the mesh needs cell and facet physical groups (name them in gmsh)")
        msh.topology.create_connectivity(tdim - 1, tdim)
        self._cell_body = np.full(msh.topology.index_map(tdim).size_local
                                  + msh.topology.index_map(tdim).num_ghosts, -1, np.int32)

        dx = ufl.Measure("dx", domain=msh, subdomain_data=mesh_data.cell_tags)
        built: list[BodyData] = []
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
            built.append(BodyData(body, i, sub, cmap, ftags, V, dx(tag),
                                         const(body.material.density), const(λ), const(μ),
                                         vertex_map=vmap))
        self.bodies = built
        for comm in (msh.comm, *(c for b in built for c in (b.V.mesh.comm,
                                                              b.V.dofmap.index_map.comm))):
            petscfree.anchor(comm)  # the PETSc communicators of its vectors and matrices
        self.entity_maps = [b.cell_map for b in self.bodies]
        self._by_name = {b.spec.name: b for b in self.bodies}

        self.W = ufl.MixedFunctionSpace(*(b.V for b in self.bodies))
        self.w = ufl.TestFunctions(self.W)
        self._gravity = fem.Constant(msh, np.zeros(self.gdim))
        self.gravity = gravity if gravity is not None else np.zeros(self.gdim)
        self.α = fem.Constant(msh, dolfinx.default_scalar_type(0.0))
        self.β = fem.Constant(msh, dolfinx.default_scalar_type(0.0))
        self.damping = damping or Damping()

        # The integration data of every pair, in one list: dolfinx compiles a form only
        # if all its integrals of a type share one subdomain_data object.
        self._interface_data: list[tuple[int, np.ndarray]] = []
        self.pairs = [self._build_pair(k, p) for k, p in enumerate(pairs)]
        _three_d_pairs(msh, surface_pairs)
        self.surface_pairs = [self._check_surfaces(p) for p in surface_pairs]
        self._fixed, self._fixed_sizes, self._load_data = [], [], []
        self.bcs = [bc for f in fixed for bc in self._build_fixed(f)]
        self.loads = [self._build_load(k, ld) for k, ld in enumerate(loads)]
        self._solvers = 0  # solvers built on this model (see options_prefix)
        self.initial = InitialSpec()
        self._built = True  # now an unknown public attribute is refused (KnownAttributes)

    @property
    def gravity(self) -> fem.Constant:
        """The body force per unit mass (m/s²); set (a vector), it sets the forms' value.

        (Assigning a vector replaced the forms' ``fem.Constant`` before: the run failed.)
        """
        return self._gravity

    @gravity.setter
    def gravity(self, g: Sequence[float] | np.ndarray | fem.Constant) -> None:
        self._gravity.value[:] = gravity_value(g, self.gdim)

    @property
    def damping(self) -> Damping:
        """The Rayleigh damping; set, it sets the forms' α and β with it.

        The fast solver reads the dataclass, the forms (the reference solver, the energy
        ledger's dissipation) the constants: a model whose damping a notebook set after
        it was built ran with both (measured on the Goda case: u_x 0.5893 mm for the
        0.5882 mm of the damping set).
        """
        return self._damping

    @damping.setter
    def damping(self, damping: Damping) -> None:
        if not isinstance(damping, Damping):
            raise TypeError(f"damping: expected a Damping, got {type(damping).__name__}")
        self._damping = damping
        self.α.value, self.β.value = damping.alpha, damping.beta

    def pair_bodies(self) -> list[tuple[int, int, str]]:
        """Each pair's slave and master body indices and its contact surface group.

        Conforming pairs first (their interface), then general ones (their slave surface).
        """
        out = [(p.slave, p.master, p.spec.interface) for p in self.pairs]
        return out + [(self.body(p.slave).index, self.body(p.master).index, p.slave_surface)
                      for p in self.surface_pairs]

    # --- set-up -------------------------------------------------------------------

    def _build_pair(self, k: int, pair: ContactPair) -> PairData:
        msh, data = self.mesh, self.mesh_data
        tdim = msh.topology.dim
        s, m = self.body(pair.slave).index, self.body(pair.master).index
        assert data.facet_tags is not None
        facets = data.facet_tags.find(group_tag(data, pair.interface, tdim - 1))
        integration = fem.compute_integration_domains(fem.IntegralType.interior_facet,
                                                      msh.topology, facets)
        _check_interface(self, pair, facets, integration)
        # Reorder so that '+' is always the slave: unordered data gives wrong numbers.
        d = integration.reshape(-1, 4).copy()
        flip = self._cell_body[d[:, 0]] != s
        d[flip] = d[flip][:, [2, 3, 0, 1]]
        if not (np.all(self._cell_body[d[:, 0]] == s) and np.all(self._cell_body[d[:, 2]] == m)):
            raise MeshError(f"interface '{pair.interface}' does not lie between "
                            f"'{pair.slave}' and '{pair.master}'")
        tag = 1000 + k
        self._interface_data.append((tag, d.ravel()))
        try:
            rule = interface_quadrature(msh, self.degree)
        except ValueError:
            raise MeshError(f"interface '{pair.interface}': conforming contact on quadratic "
                            "tetrahedra is not supported (the six-node triangle's vertices "
                            "take no share of a uniform pressure, so nodal pressures would "
                            "be wrong): mesh the bodies with hexahedra (gmsh Recombine), or "
                            "use linear tetrahedra (mesh.degree = 1)") from None
        dS = ufl.Measure("dS", domain=msh, subdomain_data=self._interface_data,
                         metadata=rule)(tag)
        n = -ufl.FacetNormal(msh)("+")  # outward normal of the master ('-') side
        c = lambda v: fem.Constant(msh, dolfinx.default_scalar_type(v))  # noqa: E731
        return PairData(pair, s, m, d, dS, n, forms.ContactLaw.of(pair, c))

    def _check_surfaces(self, pair: SurfacePair) -> SurfacePair:
        """A general pair whose surfaces lie on its bodies' boundaries.

        A surface group may lie on several bodies (a conforming interface shared by the
        two, or one group naming facets of both): each side of the pair takes the
        group's facets on its own body (:func:`breakwater.contact.surfaces.surface_dofs`).
        Whether the bodies start overlapped beyond what the pair's search sees is the
        pair's static check (:meth:`breakwater.model.pairs.Pair.static_check`), which the
        static stage runs before it looks for the initial state.
        """
        for role, body, group in (("slave", pair.slave, pair.slave_surface),
                                  *(("master", pair.master, g) for g in pair.master_groups)):
            index = self.body(body).index
            counts = self._facet_counts(group)
            if counts[index] == 0:
                found = [b.spec.name for b, c in zip(self.bodies, counts, strict=True) if c]
                if not found:
                    raise MeshError(f"contact.{pair.name}.{role}_surface: '{group}' has "
                                    "no facet on any body")
                raise MeshError(f"contact.{pair.name}.{role}_surface: '{group}' lies on "
                                f"body '{', '.join(found)}', not on the {role} '{body}' "
                                f"(facet groups on '{body}': "
                                f"{', '.join(self.facet_groups_on(body)) or 'none'})")
        return pair


def _finite(msh: dolfinx.mesh.Mesh) -> dolfinx.mesh.Mesh:
    """The mesh, refused if a node has a non-finite coordinate (NaN, inf), on every rank.

    Before, such a node (a .msh written with ``nan``) ended the case build in a
    LinAlgError traceback (the rigid modes' eigenvalues).

    Raises:
        MeshError: One line: how many nodes, and where the first (in the input's node
            order: the same line for any number of ranks).
    """
    geometry = msh.geometry
    owned = geometry.index_map().size_local
    x = geometry.x[:owned, :geometry.dim]
    bad = np.flatnonzero(~np.isfinite(x).all(axis=1))
    count = msh.comm.allreduce(len(bad))
    if not count:
        return msh
    first = None
    if len(bad):
        k = bad[np.argmin(geometry.input_global_indices[bad])]
        first = (int(geometry.input_global_indices[k]), x[k].tolist())
    _, where = min(f for f in msh.comm.allgather(first) if f is not None)
    raise MeshError(f"the mesh has {count} node(s) with a non-finite coordinate (NaN or "
                    f"inf), the first at ({', '.join(f'{c:.4g}' for c in where)}): fix the "
                    "mesh file's node coordinates")


def _check_interface(model: ContactModel, pair: ContactPair, facets: np.ndarray,
                     integration: np.ndarray) -> None:
    """Refuse a conforming pair's group that is not the face its bodies share (one line).

    No facet between two cells: :func:`_no_interface`. Facets on one body's outer
    boundary (a block overhanging its support, its whole base in the group): the pair's
    integral dropped the overhang's facets, its node pairing did not, and the run failed
    in the static stage with "is not conforming: 22 slave nodes, 13 master nodes".
    """
    msh, comm, cell_body = model.mesh, model.comm, model._cell_body
    if comm.allreduce(len(facets)) == 0 or comm.allreduce(integration.size) == 0:
        raise _no_interface(pair.interface, model.mesh_data, comm)
    names = [b.spec.name for b in model.bodies]
    outer = np.intersect1d(facets, dolfinx.mesh.exterior_facet_indices(msh.topology))
    cells = fem.compute_integration_domains(fem.IntegralType.exterior_facet,
                                            msh.topology, outer).reshape(-1, 2)[:, 0]
    count = comm.allreduce(len(cells))
    if count == 0:
        return
    bodies = set(cell_body[cells].tolist())
    found = sorted({names[i] if i >= 0 else "no body"
                    for part in comm.allgather(bodies) for i in part})
    total = count + comm.allreduce(integration.size // 4)
    raise MeshError(f"contact.{pair.interface}: {count} of the {total} facets of its "
                    f"group lie on the outer boundary of {', '.join(found)} "
                    f"alone, not between '{pair.slave}' and '{pair.master}': a conforming "
                    "pair's group is the face the two bodies share; leave the rest (an "
                    "overhang, the free crest) out of the group")


def _pair_names_once(pairs: Sequence[ContactPair], surface_pairs: Sequence[SurfacePair]
                     ) -> None:
    """Refuse two contact pairs of one name (a model built in Python).

    A conforming pair is named by its interface group, a general pair by its name (the
    case's ``[contact.<name>]``, given once; a case from Python refuses a name given
    twice). The model took both, the same contact twice, and named their history
    columns and summary entries by their index instead.

    Raises:
        CaseError: The first name given twice (one line).
    """
    names = [p.interface for p in pairs] + [p.name for p in surface_pairs]
    twice = next((n for k, n in enumerate(names) if n in names[:k]), None)
    if twice is not None:
        raise CaseError(f"contact '{twice}': two pairs of this name (each pair once: a "
                        "conforming pair is named by its interface group, a general pair "
                        "by its name)")


def _three_d_pairs(msh: dolfinx.mesh.Mesh, surface_pairs: Sequence[SurfacePair]) -> None:
    """Refuse what a 3-D general pair cannot do (:func:`~.pairs.three_d_general`, hexahedra).

    Raises:
        MeshError: The first such pair's reason (one line).
    """
    for p in surface_pairs if msh.geometry.dim == 3 else ():
        why = three_d_general(p.integration) or (
            None if msh.topology.cell_type == dolfinx.mesh.CellType.tetrahedron
            else HEXAHEDRA)
        if why:
            raise MeshError(f"contact '{p.name}': {why}")


def _no_interface(name: str, data: gmshio.MeshData, comm: MPI.Comm) -> MeshError:
    """A conforming pair named after a group with no facet between two cells (one line).

    It names the facet groups that do lie between two bodies, and ``slave_surface`` /
    ``master_surface`` for surfaces meshed apart.
    """
    msh, tdim = data.mesh, data.mesh.topology.dim
    shared = [group for group, (dim, tag) in sorted(data.physical_groups.items())
              if dim == tdim - 1 and comm.allreduce(fem.compute_integration_domains(
                  fem.IntegralType.interior_facet, msh.topology,
                  data.facet_tags.find(tag)).size) > 0]
    apart = ("for surfaces meshed apart give slave_surface and master_surface" if tdim == 2
             else "in 3D either give slave_surface and master_surface (a general pair: "
             "tetrahedra) or mesh the bodies together so that they share the "
             "interface's nodes, e.g. gmsh's BooleanFragments (OpenCASCADE) or one Extrude "
             "of both")
    return MeshError(f"contact.{name}: interface '{name}' has no facet shared by two cells: "
                     "a conforming pair's name is a facet group between its two bodies (such "
                     f"groups here: {', '.join(shared) or 'none'}); {apart}")
