"""Node pairs of a conforming contact interface, identical on every rank.

On a conforming interface each slave node has a master node at the same place. The
pairs, their master normals and, at run time, nodal values of both sides are gathered
on every rank: the interface is small (one dimension below the bulk), and every rank
then takes the same decisions, whatever the partition. Also the interface helpers of
the initial state (:mod:`breakwater.statics.initial`,
:mod:`breakwater.statics.relaxation`): the mean
facet length of a pair and the creep velocities of a frictional static state.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import dolfinx
import numpy as np
from dolfinx import fem
from mpi4py import MPI

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from breakwater.common.errors import MeshError
from breakwater.model.mesh import facet_type, group_tag
from breakwater.model.model import ContactModel, PairData
from breakwater.model.pairs import facet_size

RELEASE = 100.0
"""Slip speed of a released body's slave nodes at t = 0, in units of χ: the law then
carries μp to 5e-5 (:func:`release_velocities`, :mod:`breakwater.statics.relaxation`)."""


def _owned_interface_blocks(V: fem.FunctionSpace, facets: np.ndarray) -> np.ndarray:
    fdim = V.mesh.topology.dim - 1
    V.mesh.topology.create_connectivity(fdim, V.mesh.topology.dim)
    blocks = fem.locate_dofs_topological(V, fdim, facets)
    return blocks[blocks < V.dofmap.index_map.size_local]


class InterfaceNodes:
    """The slave/master node pairs of one contact pair.

    Attributes:
        x: Node coordinates, shape ``(n, gdim)``, sorted, the same on every rank.
        normal: Master outward unit normal at each node (facet normals averaged).
        facet_size: The size of the smallest facet at each node (m; :func:`breakwater.
            model.pairs.facet_size`).

    """

    def __init__(self, model: ContactModel, pair: PairData) -> None:
        self.comm = comm = model.comm
        self.gdim = gdim = model.gdim
        self.pair = pair
        tag = group_tag(model.mesh_data, pair.spec.interface, model.mesh.topology.dim - 1)
        sides = []
        for body in (model.bodies[pair.slave], model.bodies[pair.master]):
            blocks = _owned_interface_blocks(body.V, body.facet_tags.find(tag))
            x = body.V.tabulate_dof_coordinates()[blocks, :gdim]
            allx = np.vstack(comm.allgather(x)) if comm.size > 1 else x
            sides.append((blocks, x, allx))
        (bs, xs, allxs), (bm, xm, allxm) = sides
        if len(allxs) != len(allxm):
            raise MeshError(f"interface '{pair.spec.interface}' is not conforming: "
                            f"{len(allxs)} slave nodes, {len(allxm)} master nodes")
        scale = max(float(np.ptp(allxs, axis=0).max()), 1e-300)
        order_s = np.lexsort(np.round(allxs / scale, 9).T[::-1])
        order_m = np.lexsort(np.round(allxm / scale, 9).T[::-1])
        if not np.allclose(allxs[order_s], allxm[order_m], rtol=0, atol=1e-9 * scale):
            raise MeshError(f"interface '{pair.spec.interface}' is not conforming: "
                            "slave and master nodes do not coincide")
        self.x = allxs[order_s]
        self.size = len(self.x)
        # Position in the sorted list of every node this rank owns.
        offsets_s = np.cumsum([0, *comm.allgather(len(xs))])[comm.rank]
        offsets_m = np.cumsum([0, *comm.allgather(len(xm))])[comm.rank]
        pos_s = np.empty(len(allxs), np.int64)
        pos_s[order_s] = np.arange(len(allxs))
        pos_m = np.empty(len(allxm), np.int64)
        pos_m[order_m] = np.arange(len(allxm))
        self._slave = (bs, pos_s[offsets_s:offsets_s + len(bs)])
        self._master = (bm, pos_m[offsets_m:offsets_m + len(bm)])
        self.normal = self._normals(model, pair, comm)
        self.tangents = _tangent_basis(self.normal)

    def _normals(self, model: ContactModel, pair: PairData, comm: MPI.Comm) -> np.ndarray:
        """Average of the master outward facet normals around each node."""
        msh = model.mesh
        tdim, gdim = msh.topology.dim, self.gdim
        data = pair.facet_data
        c2f = msh.topology.connectivity(tdim, tdim - 1)
        facets = np.array([c2f.links(c)[lf] for c, lf in data[:, :2]], dtype=np.int32)
        cells = data[:, 0]
        fx = dolfinx.mesh.entities_to_geometry(msh, tdim - 1, facets)
        cx = dolfinx.mesh.entities_to_geometry(msh, tdim, cells)
        X = msh.geometry.x[:, :gdim]
        # A facet's vertices: an interval's 2, a triangle's 3, a quadrilateral's 4 (in
        # dolfinx's tensor order: v₃ is opposite v₀).
        corners = dolfinx.cpp.mesh.cell_num_vertices(facet_type(msh))
        degree, gdegree = model.degree, msh.geometry.cmaps[0].degree
        local = []
        for f, c in zip(fx, cx, strict=True):
            v = X[f[:corners]]
            if gdim == 2:
                t = v[1] - v[0]
                n = np.array([t[1], -t[0]])
            else:
                n = np.cross(v[1] - v[0], v[2] - v[0])
            n /= np.linalg.norm(n)
            if np.dot(X[c].mean(axis=0) - v.mean(axis=0), n) < 0:  # point into the slave
                n = -n
            local.append((facet_nodes(X[f], corners, degree, gdegree), n,
                          float(facet_size(v))))
        facet_list = [item for part in comm.allgather(local) for item in part]
        normal = np.zeros((self.size, gdim))
        self.facet_size = np.full(self.size, np.inf)
        scale = max(float(np.ptp(self.x, axis=0).max()), 1e-300)
        for points, n, size in facet_list:
            d = np.linalg.norm(self.x[None, :, :] - points[:, None, :], axis=2)
            at = d.argmin(axis=1)
            if d[np.arange(len(points)), at].max() > 1e-9 * scale:
                raise MeshError(f"interface '{pair.spec.interface}' is not conforming: a "
                                "facet's node is not an interface node")
            normal[at] += n
            np.minimum.at(self.facet_size, at, size)
        length = np.linalg.norm(normal, axis=1)
        if np.any(length == 0):
            raise MeshError(f"interface '{pair.spec.interface}': a node lies on no facet")
        return normal / length[:, None]

    def gather(self, slave: np.ndarray, master: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Nodal values of both sides on every rank.

        Args:
            slave: Local array of a slave-body Function (``f.x.array``).
            master: Local array of a master-body Function.

        Returns:
            ``(s, m)``, each of shape ``(n, gdim)``, in the order of :attr:`x`.

        """
        out = np.zeros((2, self.size, self.gdim))
        for k, ((blocks, pos), arr) in enumerate(((self._slave, slave),
                                                  (self._master, master))):
            out[k, pos] = arr.reshape(-1, self.gdim)[blocks]
        self.comm.Allreduce(MPI.IN_PLACE, out, op=MPI.SUM)
        return out[0], out[1]

    def scatter_slave(self, values: np.ndarray, slave: np.ndarray,
                      mask: np.ndarray | None = None) -> None:
        """Write nodal values into the owned entries of a slave-body array."""
        blocks, pos = self._slave
        if mask is not None:
            keep = mask[pos]
            blocks, pos = blocks[keep], pos[keep]
        slave.reshape(-1, self.gdim)[blocks] = values[pos]

    def tangential(self, v: np.ndarray) -> np.ndarray:
        """Tangential part (I − n⊗n) v of nodal vectors."""
        return forms.tangential_part(v, self.normal)

    def contact_state(self, u_s: np.ndarray, u_m: np.ndarray, v_s: np.ndarray | None = None,
                      v_m: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """The pair's contact law (:class:`forms.ContactLaw`) at the nodes (collective).

        The nodes are the interface's quadrature points (Gauss–Lobatto), so these are
        the values the residual uses: the same law object, evaluated on the nodal
        arrays with the current values of its parameters.

        Args:
            u_s: Local array of the slave displacement (``f.x.array``).
            u_m: Local array of the master displacement.
            v_s: Local array of the slave velocity (None: at rest).
            v_m: Local array of the master velocity.

        Returns:
            Arrays in the order of :attr:`x`, the same on every rank: ``gap``
            g_n = (u_s − u_m)·n + g₀ (m), ``pressure`` ε_n ⟨−g_n⟩₊ (Pa), ``slip``
            (I − n⊗n)(u_s − u_m) (m), ``slip_velocity`` v_T = (I − n⊗n)(v_s − v_m)
            (m/s) and ``friction_traction`` −μ p v_T / sqrt(|v_T|² + χ²) on the slave
            (Pa); the last three of shape ``(n, gdim)``.
        """
        law = self.pair.law.values()
        us, um = self.gather(u_s, u_m)
        gap = law.gap(us, um, self.normal)
        pressure = law.normal.pressure(gap)
        if v_s is None or v_m is None:
            v_T = np.zeros_like(us)
        else:
            vs, vm = self.gather(v_s, v_m)
            v_T = self.tangential(vs - vm)
        return {"gap": gap, "pressure": pressure, "slip": self.tangential(us - um),
                "slip_velocity": v_T, "friction_traction": law.friction.traction(pressure, v_T)}


def facet_nodes(x: np.ndarray, corners: int, degree: int, gdegree: int) -> np.ndarray:
    """The displacement nodes of a facet, from its geometry nodes ``x``.

    The same points as the function space's DOF coordinates, for any facet shape
    (trapezoids, warped or curved facets): the corners for degree 1; for degree 2 the
    geometry nodes themselves where the geometry is quadratic, else the corners' map
    (linear, bilinear in dolfinx's tensor order: v₃ opposite v₀) at the P2 points.

    Args:
        x: The facet's geometry nodes (dolfinx's order: the corners first).
        corners: Its vertices: 2 (interval), 3 (triangle) or 4 (quadrilateral).
        degree: The displacement's degree (1 or 2).
        gdegree: The geometry's degree.
    """
    v = x[:corners]
    if degree == 1:
        return v
    if gdegree == degree:
        return x
    if corners == 4:
        s = np.array([0.0, 0.5, 1.0])
        ξ, η = (a.ravel()[:, None] for a in np.meshgrid(s, s))
        return (v[0] * (1 - ξ) * (1 - η) + v[1] * ξ * (1 - η) + v[2] * (1 - ξ) * η
                + v[3] * ξ * η)
    mid = [0.5 * (v[a] + v[b]) for a in range(corners) for b in range(a + 1, corners)]
    return np.vstack([v, *mid])


def _tangent_basis(normal: np.ndarray) -> np.ndarray:
    """Orthonormal tangent vectors at each node, shape ``(n, gdim − 1, gdim)``.

    In 2D the tangent is the normal turned clockwise, so that +x is positive on a
    horizontal interface with an upward master normal.
    """
    gdim = normal.shape[1]
    if gdim == 2:
        return np.stack([normal[:, 1], -normal[:, 0]], axis=1)[:, None, :]
    helper = np.where(np.abs(normal[:, [0]]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    t1 = np.cross(normal, helper)
    t1 /= np.linalg.norm(t1, axis=1)[:, None]
    t2 = np.cross(normal, t1)
    return np.stack([t1, t2], axis=1)


def interface_nodes(model: ContactModel) -> Sequence[InterfaceNodes]:
    """The node pairs of every contact pair of a model."""
    return [InterfaceNodes(model, p) for p in model.pairs]


def creep_velocities(model: ContactModel, free: Sequence[PairData],
                      u: Sequence[fem.Function], v: Sequence[fem.Function], τ: float) -> None:
    """Add to the slave's interface nodes the slip velocity of the static state, Δu_T/τ.

    With it the velocity law carries at t = 0 exactly the friction of the static state
    (the quadrature points are the nodes), so that the dynamics starts in equilibrium
    (a₀ = 0 without damping) instead of from zero friction. These velocities are the
    law's creep, ≤ χ·(a few) (1e-10 m/s at the paper's χ): the bodies start at rest.
    """
    ids = {id(p) for p in free}
    for nodes in interface_nodes(model):
        p = nodes.pair
        if id(p) not in ids:
            continue
        us, um = nodes.gather(u[p.slave].x.array, u[p.master].x.array)
        vs, _ = nodes.gather(v[p.slave].x.array, v[p.master].x.array)
        nodes.scatter_slave(vs + nodes.tangential(us - um) / τ, v[p.slave].x.array)
        v[p.slave].x.scatter_forward()


def release_velocities(model: ContactModel, held: Sequence[PairData],
                       directions: Sequence[np.ndarray], v: Sequence[fem.Function],
                       speed: float = RELEASE) -> None:
    """Start the held pairs' slave nodes sliding: ``v += speed·χ·d`` (collective).

    ``d`` is the unit tangential part at each node of the pair's sliding direction
    (``directions``, one vector per pair: the direction in which the held state's
    shear pushes the slave body). At ``speed`` ≫ 1 the regularised law carries
    μp(1 − 1/(2 speed²)) against ``d`` at t = 0, the friction of sliding, instead of
    none at v = 0. Where the pair is open it carries none either way.
    """
    ids = {id(p): d for p, d in zip(held, directions, strict=True)}
    for nodes in interface_nodes(model):
        p = nodes.pair
        if id(p) not in ids:
            continue
        d = nodes.tangential(np.broadcast_to(ids[id(p)], (nodes.size, nodes.gdim)))
        size = np.linalg.norm(d, axis=1)
        keep = size > 1e-12
        χ = float(p.law.friction.χ.value)
        vs, _ = nodes.gather(v[p.slave].x.array, v[p.master].x.array)
        vs[keep] += speed * χ * d[keep] / size[keep, None]
        nodes.scatter_slave(vs, v[p.slave].x.array)
        v[p.slave].x.scatter_forward()


def mean_facet_length(model: ContactModel, pair: PairData) -> float:
    """Mean facet size h of a contact interface (m).

    In 2D the facets' mean length; in 3D the side of the square (quadrilaterals) or of
    the equilateral triangle of their mean area.
    """
    measure = model.assemble(model.form(1.0 * pair.dS))
    mean = measure / model.comm.allreduce(len(pair.facet_data))
    if model.mesh.topology.dim == 2:
        return mean
    triangle = facet_type(model.mesh) == dolfinx.mesh.CellType.triangle
    return math.sqrt(mean * (4 / math.sqrt(3) if triangle else 1.0))
