"""The 3D counterpart of :func:`breakwater.model.mesh.check_cells`: a tetrahedral mesh's cells.

A tetrahedron whose four corners lie in one plane (or on one line, or at one point) has
no volume: its stiffness is NaN (0/0 in the inverse Jacobian), and the run failed far
from the cause (a MUMPS error, a Newton failure, or "no static equilibrium" for the flat
tetrahedron of ``tests/bad_cases/run/c4_*``, away from the contact surfaces); a 10-node
tetrahedron folded by a mid-edge node ran to the end (``c5_*``).
:func:`check_tetrahedra` refuses them when the mesh is read,
in one line naming the file, the cell (gmsh element tag) and its centre, with the
thresholds of the 2D check (:data:`~breakwater.model.meshcells.DEGENERATE`,
:data:`~breakwater.model.meshcells.THIN`) on the same measure: the smallest height over the
longest edge.

Hexahedra are not checked here (breakwater's generator makes them structured).
"""

from __future__ import annotations

import logging
import pathlib

import gmsh
import numpy as np

from breakwater.common.errors import MeshError
from breakwater.model.meshcells import DEGENERATE, THIN

__all__ = ["check_tetrahedra", "curved_tet_jacobian", "tet_quality"]

log = logging.getLogger("breakwater.model.mesh")

_FACES = np.array([[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]])
"""A tetrahedron's faces, face k opposite corner k."""
_EDGES = np.array([[0, 1], [1, 2], [2, 0], [0, 3], [2, 3], [1, 3]])
"""The edges of gmsh's 10-node tetrahedron (type 11): its nodes 4..9 are their midpoints
(gmsh's reference coordinates, ``getElementProperties(11)``)."""


def tet_quality(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Signed volume and smallest height over the longest edge of tetrahedra.

    The 2D check's measure (a triangle's smallest height, on its longest edge, over
    that edge) in 3D: the smallest height is ``3 |V| / A_max`` (on the largest face),
    so the quality is ``3 |V| / (A_max l_max)``: √(2/3) ≈ 0.816 for the regular
    tetrahedron, 0 for a flat one, and ``t / l`` for a slab of thickness ``t`` (a
    sliver), linear in the thinness as the 2D one (the normalised volume
    ``6√2 V / l_max³`` falls as its square on a needle, so the 2D thresholds would not
    mean the same).

    Args:
        corners: The corner coordinates, ``(cells, 4, 3)``, in the cells' vertex order.

    Returns:
        ``(volume, quality)``: the signed volume ((x1 − x0) × (x2 − x0) · (x3 − x0) / 6,
        positive in gmsh's orientation) and the quality.
    """
    # Relative to corner 0: far from the origin absolute products lose the volume.
    local = corners - corners[:, :1]
    volume = np.einsum("ij,ij->i", local[:, 1], np.cross(local[:, 2], local[:, 3])) / 6
    f = local[:, _FACES]  # (cells, face, corner, xyz)
    area = 0.5 * np.linalg.norm(np.cross(f[:, :, 1] - f[:, :, 0], f[:, :, 2] - f[:, :, 0]),
                                axis=-1).max(axis=1)
    longest = np.linalg.norm(local[:, _EDGES[:, 1]] - local[:, _EDGES[:, 0]], axis=-1).max(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        quality = np.where(area * longest > 0, 3 * np.abs(volume) / (area * longest), 0.0)
    return volume, quality


def _p2_tet_derivatives() -> np.ndarray:
    """∂N/∂(ξ, η, ζ) of the 10-node tetrahedron at its own nodes, ``(node, 3, 10)``."""
    ref = np.vstack([np.zeros(3), np.eye(3)])  # the corners; the mid-edge nodes follow
    points = np.vstack([ref, 0.5 * (ref[_EDGES[:, 0]] + ref[_EDGES[:, 1]])])
    lam = np.column_stack([1 - points.sum(axis=1), points])  # barycentric, (node, 4)
    grad = np.vstack([-np.ones(3), np.eye(3)])  # ∇λ_k, (4, 3)
    out = np.zeros((len(points), 3, 10))
    for k in range(4):  # N_k = λ_k (2 λ_k − 1)
        out[:, :, k] = (4 * lam[:, k] - 1)[:, None] * grad[k]
    for e, (i, j) in enumerate(_EDGES):  # N_ij = 4 λ_i λ_j
        out[:, :, 4 + e] = 4 * (lam[:, i, None] * grad[j] + lam[:, j, None] * grad[i])
    return out


_P2_TET_DN = _p2_tet_derivatives()


def curved_tet_jacobian(x: np.ndarray) -> np.ndarray:
    """The smallest Jacobian of 10-node tetrahedra at their nodes over the corners' one.

    The 3D :func:`~breakwater.model.mesh.curved_jacobian`.

    Args:
        x: The nodes' coordinates, ``(cells, 10, 3)`` in gmsh's order.

    Returns:
        ``min det J(node) / det J(straight cell)`` per cell: 1 for a straight-edged
        cell, ≤ 0 where a mid-edge node moved far enough to fold the cell.
    """
    local = x - x[:, :1]
    J = np.einsum("qan,cnd->cqad", _P2_TET_DN, local)  # (cells, node, ∂, coordinate)
    det = np.linalg.det(J)
    straight = np.linalg.det(local[:, 1:4])
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(straight != 0, det.min(axis=1) / straight, 0.0)


def check_tetrahedra(path: pathlib.Path) -> None:
    """Refuse degenerate, folded or overlapping tetrahedra of the current gmsh model (rank 0).

    Checked on the corners of each cell: a smallest height below
    :data:`~breakwater.model.meshcells.DEGENERATE` of the longest edge is refused (no
    volume), below :data:`~breakwater.model.meshcells.THIN` warned about once (the thinnest
    cell). A 10-node tetrahedron is refused where its Jacobian at one of its nodes
    falls to ``DEGENERATE`` of the straight cell's or changes sign
    (:func:`curved_tet_jacobian`: a mid-edge node moved across the cell). Two cells on
    the same side of their shared face overlap (a folded mesh, an inverted cell among
    its neighbours), whatever each volume's orientation. Other cells (hexahedra), and
    cells with a non-finite node (refused when the model is built, naming the node), are
    left alone.

    Raises:
        MeshError: One line naming the file, the cell (gmsh element tag) and its centre.
    """
    tags, coords, _ = gmsh.model.mesh.getNodes()
    xyz = np.zeros((int(tags.max()) + 1, 3))
    xyz[tags.astype(np.int64)] = coords.reshape(-1, 3)
    for etype, etags, enodes in zip(*gmsh.model.mesh.getElements(3), strict=True):
        if etype not in (4, 11):  # 4- and 10-node tetrahedra
            continue
        all_nodes = enodes.astype(np.int64).reshape(len(etags), -1)
        # A cell with a non-finite node (nan in the file) is left to the model's check,
        # which names the node (model._finite): here it would be "degenerate" at nan.
        finite = np.isfinite(xyz[all_nodes]).all(axis=(1, 2))
        all_nodes, etags = all_nodes[finite], etags[finite]
        if not len(etags):
            continue
        nodes = all_nodes[:, :4]

        def where(k: int, nodes: np.ndarray = nodes, etags: np.ndarray = etags) -> str:
            c = xyz[nodes[k]].mean(axis=0)
            return f"cell {etags[k]} at ({c[0]:.6g}, {c[1]:.6g}, {c[2]:.6g})"

        quality = tet_quality(xyz[nodes])[1]
        worst = int(np.argmin(quality))
        if quality[worst] < DEGENERATE:
            raise MeshError(f"{path}: {where(worst)} is degenerate: its smallest height is "
                            f"{quality[worst]:.1e} of its longest edge, below "
                            f"{DEGENERATE:g} (no volume: its corners in one plane; remesh)")
        thin = int(np.count_nonzero(quality < THIN))
        if thin:
            log.warning("%s: %d thin cell(s), the thinnest %s: smallest height %.1e of its "
                        "longest edge, below %g (poor accuracy and conditioning)", path, thin,
                        where(worst), quality[worst], THIN)
        if etype == 11:
            ratio = curved_tet_jacobian(xyz[all_nodes])
            k = int(np.argmin(ratio))
            if ratio[k] < DEGENERATE:
                raise MeshError(f"{path}: curved {where(k)} folds: its Jacobian at a node is "
                                f"{ratio[k]:.1e} of its corners' (a mid-edge node too far "
                                "off its edge; refine there or remesh)")
        _check_faces(path, xyz, nodes, etags)


def _check_faces(path: pathlib.Path, xyz: np.ndarray, nodes: np.ndarray,
                 etags: np.ndarray) -> None:
    """Refuse two tetrahedra on the same side of their shared face (an overlap)."""
    faces, sides = [], []
    for k in range(4):
        face = np.sort(nodes[:, _FACES[k]], axis=1)
        a, b, c, d = (xyz[face[:, 0]], xyz[face[:, 1]], xyz[face[:, 2]], xyz[nodes[:, k]])
        sides.append(np.sign(np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a)))
        faces.append(face)
    face = np.concatenate(faces)
    side = np.concatenate(sides)
    owner = np.tile(etags.astype(np.int64), 4)
    order = np.lexsort((face[:, 2], face[:, 1], face[:, 0]))
    face, side, owner = face[order], side[order], owner[order]
    same = np.all(face[1:] == face[:-1], axis=1) & (side[1:] == side[:-1])
    if same.any():
        j = int(np.flatnonzero(same)[0])
        mid = xyz[face[j]].mean(axis=0)
        raise MeshError(f"{path}: cells {owner[j]} and {owner[j + 1]} overlap at "
                        f"({mid[0]:.6g}, {mid[1]:.6g}, {mid[2]:.6g}): both lie on the same "
                        "side of their shared face (a folded mesh or an inverted cell; "
                        "remesh)")
