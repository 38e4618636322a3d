"""Where a contact model's groups lie: bodies by name, facet groups, fixed groups, loads.

:class:`ModelGroups` finds the named groups of the mesh on the bodies and builds the
Dirichlet conditions and the load measures (on the data
:class:`~breakwater.model.model.ContactModel` builds).
"""

from __future__ import annotations

from collections.abc import Sequence

import dolfinx
import numpy as np
import ufl
from dolfinx import fem

from breakwater.common.errors import MeshError
from breakwater.loads.fields import StagedField
from breakwater.model.mesh import group_tag, group_vertices
from breakwater.model.parts import BodyData, Fixed, LoadData, SurfaceLoad
from breakwater.model.residual import ModelForms

__all__ = ["ModelGroups"]


def _owned_measure(msh: dolfinx.mesh.Mesh, dim: int, entities: np.ndarray) -> float:
    """The measure of this rank's share of entities: owned points' count, facets' area/length.

    Facets are taken flat between their vertices (a quadrilateral as two triangles):
    exact for the plane faces a fixed boundary usually is.
    """
    owned = entities[entities < msh.topology.index_map(dim).size_local]
    if dim == 0 or not len(owned):
        return float(len(owned))
    msh.topology.create_connectivity(dim, 0)
    x = msh.geometry.x[dolfinx.mesh.entities_to_geometry(msh, dim, owned, False)]
    if dim == 1:
        return float(np.linalg.norm(x[:, 1] - x[:, 0], axis=1).sum())
    area = 0.5 * np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1)
    if msh.topology.cell_type == dolfinx.mesh.CellType.hexahedron:  # v3 opposite v0
        area += 0.5 * np.linalg.norm(np.cross(x[:, 1] - x[:, 3], x[:, 2] - x[:, 3]), axis=1)
    return float(area.sum())


class ModelGroups(ModelForms):
    """The model's named groups on its bodies: look-ups, fixed boundaries and loads."""

    _by_name: dict[str, BodyData]
    _cell_body: np.ndarray
    _fixed: list[tuple[str, int, tuple[int, ...]]]  # group, body, components
    bcs: list[fem.DirichletBC]  # the fixed entries' components, in their order
    _fixed_sizes: list[float]  # each entry of _fixed: its area (3D), length or points
    _load_data: list[tuple[int, np.ndarray]]

    def body(self, name: str) -> BodyData:
        """The data of a body by name."""
        try:
            return self._by_name[name]
        except KeyError:
            raise KeyError(f"no body named '{name}' (bodies: {', '.join(self._by_name)})") \
                from None

    def surface_facets(self, body: str, groups: Sequence[str]) -> np.ndarray:
        """A body's facets (its submesh's, ghosts included) in any of several groups."""
        b, fdim = self.body(body), self.mesh.topology.dim - 1
        found = [b.facet_tags.find(group_tag(self.mesh_data, g, fdim)) for g in groups]
        return np.unique(np.concatenate(found)) if found else np.zeros(0, np.int32)

    def facet_groups_on(self, body: str) -> list[str]:
        """The facet groups with a facet on a body, by name (collective, every rank)."""
        fdim, index = self.mesh.topology.dim - 1, self.body(body).index
        names = sorted(name for name, (dim, _) in self.mesh_data.physical_groups.items()
                       if dim == fdim)
        return [name for name in names if self._facet_counts(name)[index] > 0]

    def _facet_counts(self, group: str) -> list[int]:
        """The number of facets of a facet group on each body (every rank)."""
        tag = group_tag(self.mesh_data, group, self.mesh.topology.dim - 1)
        return [self.comm.allreduce(len(b.facet_tags.find(tag))) for b in self.bodies]

    def _locate(self, group: str) -> list[tuple[BodyData, np.ndarray]]:
        """The bodies whose boundaries hold a facet group, and its facets in each submesh.

        A fixed group may span several bodies (a floor under two of them): each holds
        its part (it was refused, "must lie on exactly one body (found on 2)").
        """
        counts = self._facet_counts(group)
        owners = [i for i, c in enumerate(counts) if c > 0]
        if not owners:
            raise MeshError(f"fixed '{group}': facet group '{group}' has no facet on any "
                            "body's boundary")
        tag = group_tag(self.mesh_data, group, self.mesh.topology.dim - 1)
        return [(self.bodies[i], self.bodies[i].facet_tags.find(tag)) for i in owners]

    def _build_fixed(self, fixed: Fixed) -> list[fem.DirichletBC]:
        """Zero displacement components on a facet group or at a point group's vertices.

        A point group (dimension 0, gmsh ``Physical Point``) holds the components of the
        nodes at its points, as a facet group holds those of the nodes on its facets.
        """
        fdim = self.mesh.topology.dim - 1
        dim = self.mesh_data.physical_groups.get(fixed.group, (fdim, 0))[0]
        if dim == 0:
            located = [self._locate_points(fixed.group)]
        elif dim == fdim:
            located = self._locate(fixed.group)
        else:
            raise MeshError(f"fixed '{fixed.group}': physical group of dimension {dim}, "
                            f"expected a facet ({fdim}D) or point (0D) group")
        comps = range(self.gdim) if fixed.components is None else fixed.components
        bcs = []
        for body, entities in located:
            for c in comps:
                if not 0 <= c < self.gdim:
                    raise ValueError(f"fixed '{fixed.group}': component {c} out of range")
                Vc = body.V.sub(c)
                dofs = fem.locate_dofs_topological(Vc, dim, entities)
                bcs.append(fem.dirichletbc(dolfinx.default_scalar_type(0.0), dofs, Vc))
            self._fixed.append((fixed.group, body.index, tuple(comps)))
            self._fixed_sizes.append(self.comm.allreduce(
                _owned_measure(body.submesh, dim, entities)))
        return bcs

    def _locate_points(self, group: str) -> tuple[BodyData, np.ndarray]:
        """The body holding a point group, and the group's vertices in its submesh.

        Raises:
            MeshError: The group's points are on no body's vertices, or on several
                bodies (a point shared by two bodies of a conforming interface).
        """
        parent = group_vertices(self.mesh_data, group)
        found = []
        for b in self.bodies:
            assert b.vertex_map is not None
            sub = b.vertex_map.sub_topology_to_topology(parent, inverse=True)
            found.append(np.asarray(sub[sub >= 0], dtype=np.int32))
        counts = [self.comm.allreduce(len(f)) for f in found]
        owners = [i for i, c in enumerate(counts) if c > 0]
        if not owners:
            raise MeshError(f"fixed '{group}': point group '{group}' has no vertex of any "
                            "body")
        if len(owners) > 1:
            names = ", ".join(self.bodies[i].spec.name for i in owners)
            raise MeshError(f"fixed '{group}': point group '{group}' lies on several "
                            f"bodies ({names}); a fixed point group must lie on exactly one")
        body = self.bodies[owners[0]]
        body.submesh.topology.create_connectivity(0, body.submesh.topology.dim)
        return body, found[owners[0]]

    def fixed_on(self, body: str) -> list[tuple[str, tuple[int, ...]]]:
        """The fixed boundaries on a body: (facet or point group, components held)."""
        index = self.body(body).index
        return [(group, comps) for group, i, comps in self._fixed if i == index]

    def fixed_nodes(self) -> list[tuple[str, int, tuple[int, ...], np.ndarray]]:
        """Each fixed entry's group, body, components, and its nodes' coordinates here.

        The nodes (owned by this rank, not ghosts) whose components the entry holds:
        :mod:`breakwater.statics.rigidmodes` finds from them the rigid modes left free.
        """
        out, k = [], 0
        for group, index, comps in self._fixed:
            V = self.bodies[index].V
            if not comps:
                continue
            dofs = self.bcs[k].dof_indices()[0] // V.dofmap.index_map_bs
            k += len(comps)
            nodes = np.unique(dofs[dofs < V.dofmap.index_map.size_local])
            x = V.tabulate_dof_coordinates()[nodes, :self.gdim]
            out.append((group, index, comps, x))
        return out

    def fixed_summary(self) -> dict[str, dict[str, object]]:
        """What the fixed groups hold (the summary's ``fixed``), by group name.

        Each: ``components`` held (``"x"``, ``"y"``, ``"z"``), and per body it holds
        the group's ``area`` on it (m², 3D), ``length`` (m, plane strain) or ``points``.
        """
        out: dict[str, dict[str, object]] = {}
        fdim = self.mesh.topology.dim - 1
        for (group, index, comps), size in zip(self._fixed, self._fixed_sizes, strict=True):
            dim = self.mesh_data.physical_groups.get(group, (fdim, 0))[0]
            key = "points" if dim == 0 else "area" if fdim == 2 else "length"
            entry = out.setdefault(group, {"components": ["xyz"[c] for c in comps],
                                           "bodies": {}})
            bodies = entry["bodies"]
            assert isinstance(bodies, dict)
            bodies[self.bodies[index].spec.name] = {key: int(size) if dim == 0 else size}
        return out

    def _build_load(self, k: int, load: SurfaceLoad) -> LoadData:
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
            key = f" (loads.{load.name}.body)" if load.name else ""
            raise MeshError(f"facet group '{load.group}' must lie on exactly one body "
                            f"(found on {len(owners)}{': ' + names if names else ''}; name "
                            f"the body loaded{key})")
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
        x, n = ufl.SpatialCoordinate(msh), ufl.FacetNormal(msh)
        field = load.field
        if not isinstance(field, StagedField):
            return LoadData(load, index, ds, amp, load.unit_traction(x, n))
        # A field that changes at given times: its parameters in a Constant (stage 0).
        c = fem.Constant(msh, np.array(field.parameters(field.stage(0.0)), dtype=float))
        return LoadData(load, index, ds, amp, load.unit_traction(x, n, c), parameters=c,
                        stage=field.stage(0.0),
                        unit_with=lambda c0: field.traction_with(x, n, c0))
