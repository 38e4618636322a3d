"""The tetrahedra's check when a 3D mesh is read (breakwater.model.tetcells).

Reference values are the tetrahedron's elementary geometry: the regular tetrahedron's
smallest height over its edge √(2/3), a slab's height over its longest edge, and the
10-node tetrahedron's Jacobian at its nodes with one mid-edge node moved along its
edge (derived in :func:`test_a_mid_edge_node_moved_along_its_edge`).
"""

from __future__ import annotations

import logging
import pathlib

import gmsh
import numpy as np
import pytest
from mpi4py import MPI

from breakwater.common.errors import MeshError
from breakwater.common.gmshtools import gmsh_session
from breakwater.common.parallel import on_rank_zero
from breakwater.model.mesh import read_mesh
from breakwater.model.tetcells import _EDGES, curved_tet_jacobian, tet_quality

COMM = MPI.COMM_WORLD
REF = np.vstack([np.zeros(3), np.eye(3)])  # the reference tetrahedron's corners
P2 = np.vstack([REF, 0.5 * (REF[_EDGES[:, 0]] + REF[_EDGES[:, 1]])])  # its 10 nodes


def test_quality_of_the_regular_tetrahedron_far_from_the_origin():
    # Edge l = 2√2: volume l³/(6√2) = 8/3, smallest height √(2/3) l (every face alike).
    tet = np.array([[[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]], dtype=float)
    for offset in (0.0, 512345.0, 4123456.0):  # UTM-like coordinates: round-off 1e-16 × 4e6
        volume, quality = tet_quality(tet + offset)
        assert abs(volume[0]) == pytest.approx(8 / 3, rel=1e-6)
        assert quality[0] == pytest.approx(np.sqrt(2 / 3), rel=1e-6)


def test_quality_of_a_slab_is_its_thickness_over_its_longest_edge():
    # Base (0,0,0), (1,0,0), (0,1,0) (area 1/2, the largest face), apex at height t:
    # smallest height t, longest edge √2 (the base's hypotenuse) -> t/√2, linear in t.
    for t in (1e-1, 1e-3, 1e-7):
        tet = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0], [1 / 3, 1 / 3, t]]])
        assert tet_quality(tet)[1][0] == pytest.approx(t / np.sqrt(2), rel=1e-9)


def test_flat_collapsed_and_non_finite_tetrahedra_have_no_quality():
    flat = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.3, 0.3, 0]]  # four corners in a plane
    point = [[0, 0, 0]] * 4
    nan = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, np.nan]]
    assert list(tet_quality(np.array([flat, point, nan], dtype=float))[1]) == [0, 0, 0]


def test_gmsh_numbers_the_mid_edge_nodes_as_the_check_does():
    with gmsh_session():
        ref = gmsh.model.mesh.getElementProperties(11)[4].reshape(-1, 3)
    assert np.array_equal(ref, P2)


def test_a_mid_edge_node_moved_along_its_edge():
    # Node 4 (edge 0-1) moved by δ along x on the reference cell: ∂x/∂ξ gains
    # 4 (λ0 − λ1) δ (∂N4/∂ξ = 4 (λ0 − λ1)), ∂x/∂η and ∂x/∂ζ nothing, so det J = 1 + 4 (λ0 − λ1) δ:
    # its least at corner 1, 1 − 4δ (0 at δ = 1/4: the node at 3/4 of the edge).
    for delta, expected in ((0.0, 1.0), (0.1, 0.6), (0.25, 0.0), (0.3, -0.2)):
        x = P2.copy()
        x[4, 0] += delta
        assert curved_tet_jacobian(x[None])[0] == pytest.approx(expected, abs=1e-12)
    # Any affine image of a straight cell (scaled, sheared, mirrored, moved): 1.
    A = np.array([[2.0, 0.3, -0.1], [0.0, 0.5, 0.2], [0.1, 0.0, -1.5]])
    assert curved_tet_jacobian((P2 @ A.T + [5e5, 4e6, 10.0])[None])[0] == pytest.approx(1.0)


def write_msh(folder: pathlib.Path, name: str, nodes: np.ndarray, cells: list[list[int]],
              etype: int = 4) -> pathlib.Path:
    """A gmsh 2.2 file of tetrahedra in one volume group 'body' (rank 0 writes)."""
    path = folder / name
    lines = ["$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$PhysicalNames", "1",
             '3 1 "body"', "$EndPhysicalNames", "$Nodes", str(len(nodes))]
    lines += [f"{k + 1} {x:.17g} {y:.17g} {z:.17g}" for k, (x, y, z) in enumerate(nodes)]
    lines += ["$EndNodes", "$Elements", str(len(cells))]
    lines += [f"{k + 1} {etype} 2 1 1 " + " ".join(map(str, c)) for k, c in enumerate(cells)]
    lines += ["$EndElements", ""]
    on_rank_zero(COMM, lambda: path.write_text("\n".join(lines)))
    return path


def two_tetrahedra(apex: list[float], second: list[int]) -> tuple[np.ndarray, list[list[int]]]:
    """The reference tetrahedron (nodes 1-4) and a second on its face 1-2-3, apex node 5."""
    return np.vstack([REF, apex]), [[1, 2, 3, 4], second]


def test_a_valid_mesh_of_either_orientation_is_read(shared_dir):
    # The second cell below the face z = 0, numbered clockwise (negative volume) or not:
    # both are the same valid mesh (no folded or overlapping cell).
    for k, second in enumerate(([1, 3, 2, 5], [1, 2, 3, 5])):
        nodes, cells = two_tetrahedra([0.2, 0.2, -0.5], second)
        data = read_mesh(write_msh(shared_dir, f"ok{k}.msh", nodes, cells), COMM)
        assert COMM.allreduce(data.mesh.topology.index_map(3).size_local) == 2


def test_overlapping_tetrahedra_are_refused(shared_dir):
    # The apex above the face z = 0, as the first cell's: both on the same side of it.
    nodes, cells = two_tetrahedra([0.2, 0.2, 0.5], [1, 2, 3, 5])
    path = write_msh(shared_dir, "overlap.msh", nodes, cells)
    with pytest.raises(MeshError, match=r"overlap.msh: cells 1 and 2 overlap at "
                       r"\(0.333333, 0.333333, 0\): both lie on the same side"):
        read_mesh(path, COMM)  # on every rank (rank 0's refusal, broadcast)


def test_a_flat_tetrahedron_is_refused_and_a_thin_one_warned_about(shared_dir, caplog):
    nodes, cells = two_tetrahedra([0.3, 0.3, 0.0], [1, 3, 2, 5])
    path = write_msh(shared_dir, "flat.msh", nodes, cells)
    with pytest.raises(MeshError, match=r"flat.msh: cell 2 at \(0.325, 0.325, 0\) is "
                       r"degenerate: its smallest height is 0.0e\+00 of its longest edge"):
        read_mesh(path, COMM)
    # Apex 0.005 below the base: height 0.005 over the longest edge √2, 3.5e-3 < 1e-2.
    nodes, cells = two_tetrahedra([0.2, 0.2, -0.005], [1, 3, 2, 5])
    with caplog.at_level(logging.WARNING, logger="breakwater.model.mesh"):
        read_mesh(write_msh(shared_dir, "thin.msh", nodes, cells), COMM)
    if COMM.rank == 0:  # rank 0 checks the file
        assert "1 thin cell(s), the thinnest cell 2 at (0.3, 0.3, -0.00125): smallest " \
               "height 3.5e-03 of its longest edge, below 0.01" in caplog.text


def test_a_folded_ten_node_tetrahedron_is_refused(shared_dir):
    x = P2.copy()
    x[4, 0] += 0.3  # det J at corner 1: 1 − 4 × 0.3 = −0.2 (as above)
    path = write_msh(shared_dir, "folded.msh", x, [list(range(1, 11))], etype=11)
    with pytest.raises(MeshError, match=r"folded.msh: curved cell 1 at \(0.25, 0.25, 0.25\) "
                       r"folds: its Jacobian at a node is -2.0e-01 of its corners'"):
        read_mesh(path, COMM)
    x[4, 0] = 0.6  # det J ≥ 0.6: curved, accepted
    data = read_mesh(write_msh(shared_dir, "curved.msh", x, [list(range(1, 11))], etype=11),
                     COMM)
    assert data.mesh.geometry.cmaps[0].degree == 2
