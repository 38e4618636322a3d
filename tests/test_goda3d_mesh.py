"""Tests of the 3-D Goda (1994) mesh, :mod:`breakwater.meshes.goda3d` (serial and MPI).

References are the model's dimensions (Goda 1994, as restated by Stickle et al. 2011 and
``breakwater/cases/goda.toml``) and the formulas of boxes and prisms: the volume of the
mound is its trapezoidal cross-section times the flume's width, the caisson's is
``b h L``. The cells have straight edges (trilinear at worst, boxes under the block), so
dolfinx's quadrature integrates volumes and areas exactly: 1e-12 relative is round-off
over a thousand cells.
"""

from __future__ import annotations

import math
import pathlib

import dolfinx
import gmsh
import numpy as np
import pytest
import ufl
from breakwater.meshes import goda3d
from mpi4py import MPI

from breakwater.model.mesh import read_mesh

COMM = MPI.COMM_WORLD

# Goda's model (metres).
H_MOUND, CREST, SLOPE = 0.190, 0.400, 2.0
B, H, L = 0.205, 0.202, 0.205  # caisson width (x), height (y), length (z)
BASE_WIDTH = CREST + 2 * SLOPE * H_MOUND
SECTION = 0.5 * (CREST + BASE_WIDTH) * H_MOUND  # the mound's trapezoid
SLOPE_LENGTH = H_MOUND * math.hypot(1.0, SLOPE)
PATCH_H, PATCH_W, BOLT = 0.010, 0.010, 0.168
WIDE = 0.405  # a flume 200 mm wider than the block
REL = 1e-12


@pytest.fixture(scope="module")
def meshes(folder: pathlib.Path) -> dict[str, pathlib.Path]:
    """The default mesh (order 2), a wider flume's, and the default at refinement 2."""
    return {
        "default": goda3d.generate(folder / "goda3d.msh"),
        "wide": goda3d.generate(folder / "wide.msh", goda3d.Goda3DGeometry(flume_width=WIDE)),
        "fine": goda3d.generate(folder / "fine.msh", refinement=2.0, order=1),
    }


@pytest.fixture(scope="module")
def data(meshes) -> dict[str, dolfinx.io.gmsh.MeshData]:
    return {name: read_mesh(path, COMM) for name, path in meshes.items()}


def _integral(d: dolfinx.io.gmsh.MeshData, name: str) -> float:
    """The volume or area of a physical group (interior facets: ``interface``)."""
    mesh = d.mesh
    dim, tag = d.physical_groups[name]
    if dim == 3:
        measure = ufl.Measure("dx", domain=mesh, subdomain_data=d.cell_tags)(tag)
    else:
        kind = "dS" if name == goda3d.INTERFACE else "ds"
        measure = ufl.Measure(kind, domain=mesh, subdomain_data=d.facet_tags)(tag)
    one = dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(1.0))
    return COMM.allreduce(dolfinx.fem.assemble_scalar(dolfinx.fem.form(one * measure)))


def _global_cells(d: dolfinx.io.gmsh.MeshData) -> int:
    return d.mesh.topology.index_map(3).size_global


def test_groups_cell_type_and_count(data):
    d = data["default"]
    assert d.physical_groups == dict(goda3d.PHYSICAL_GROUPS)
    assert d.mesh.topology.cell_type == dolfinx.mesh.CellType.hexahedron
    assert d.mesh.geometry.cmaps[0].degree == 2
    assert d.mesh.geometry.dofmaps[0].shape[1] == 27
    assert _global_cells(d) == goda3d.Goda3DGeometry().estimated_elements() == 1032


@pytest.mark.parametrize("mesh", ["default", "wide"])
def test_cells_positively_oriented(data, mesh):
    """det J > 0 in every cell (dolfinx's node order): the integral of its sign is the
    volume; and the outward normal integrates to the faces' areas along the axes."""
    d = data[mesh]
    m = d.mesh
    det = ufl.JacobianDeterminant(m)
    dx = ufl.dx(domain=m)
    signed, volume = (COMM.allreduce(dolfinx.fem.assemble_scalar(dolfinx.fem.form(f)))
                      for f in (det / abs(det) * dx, 1.0 * dx))
    assert signed == pytest.approx(volume, rel=REL)
    n = ufl.FacetNormal(m)
    ds = ufl.Measure("ds", domain=m, subdomain_data=d.facet_tags)
    width = L if mesh == "default" else WIDE
    for name, axis, area in ((goda3d.BASE, 1, -BASE_WIDTH * width),
                             (goda3d.CAISSON_TOP, 1, B * L),
                             (goda3d.CAISSON_REAR, 0, H * L)):
        form = dolfinx.fem.form(n[axis] * ds(d.physical_groups[name].tag))
        assert COMM.allreduce(dolfinx.fem.assemble_scalar(form)) == pytest.approx(
            area, rel=REL), name


@pytest.mark.parametrize(("mesh", "width"), [("default", L), ("wide", WIDE)])
def test_volumes_and_areas(data, mesh, width):
    d = data[mesh]
    assert _integral(d, goda3d.CAISSON) == pytest.approx(B * H * L, rel=REL)
    assert _integral(d, goda3d.MOUND) == pytest.approx(SECTION * width, rel=REL)
    expected = {
        goda3d.INTERFACE: B * L,
        goda3d.BASE: BASE_WIDTH * width,
        goda3d.IMPACT: PATCH_H * PATCH_W,
        goda3d.CAISSON_FRONT: H * L - PATCH_H * PATCH_W,
        goda3d.CAISSON_REAR: H * L,
        goda3d.CAISSON_TOP: B * L,
        goda3d.CAISSON_SIDES: 2 * B * H,
        goda3d.MOUND_SIDES: 2 * SECTION,
        # The slopes and the crest beside the block along the flume, and the crest
        # under the block's footprint beyond its ends (none when the block spans it).
        goda3d.MOUND_SURFACE: (2 * SLOPE_LENGTH + CREST - B) * width + B * (width - L),
    }
    for name, area in expected.items():
        assert _integral(d, name) == pytest.approx(area, rel=REL), name


def _nodes(d: dolfinx.io.gmsh.MeshData, dim: int, tag: int) -> np.ndarray:
    """The coordinates of the geometry nodes of the tagged entities, on all ranks."""
    mesh = d.mesh
    tags = {3: d.cell_tags, 2: d.facet_tags, 0: d.peak_tags}[dim]
    entities = tags.indices[tags.values == tag]
    if dim == 3:
        nodes = mesh.geometry.dofmaps[0][entities].ravel()
    else:
        mesh.topology.create_connectivity(dim, 3)
        nodes = dolfinx.mesh.entities_to_geometry(mesh, dim, entities).ravel()
    x = np.concatenate(COMM.allgather(mesh.geometry.x[nodes]))
    return np.unique(np.round(x, 12), axis=0)


def test_interface_is_conforming(data):
    """Both bodies have the same nodes on the interface: each of its facets has a
    caisson cell on one side and a mound cell on the other (a shared facet)."""
    d = data["default"]
    mesh, groups = d.mesh, d.physical_groups
    caisson, mound = groups[goda3d.CAISSON].tag, groups[goda3d.MOUND].tag
    interface = d.facet_tags.indices[d.facet_tags.values == groups[goda3d.INTERFACE].tag]
    mesh.topology.create_connectivity(2, 3)
    f2c = mesh.topology.connectivity(2, 3)
    imap = mesh.topology.index_map(3)
    body = np.full(imap.size_local + imap.num_ghosts, -1)
    body[d.cell_tags.indices] = d.cell_tags.values
    owned = interface[interface < mesh.topology.index_map(2).size_local]
    shared = all(sorted(body[f2c.links(f)]) == sorted((caisson, mound)) for f in owned)
    assert COMM.allreduce(shared, op=MPI.LAND)  # the same decision on every rank
    plan = goda3d._plan(goda3d.Goda3DGeometry(), 1.0)
    assert COMM.allreduce(len(owned)) == plan.across * sum(plan.nz)  # 5 x 6 facets
    # The caisson's nodes on its base and the mound's under the block: the same set,
    # 2 n + 1 per direction (quadratic) for n cells across and along the block.
    y1 = H_MOUND
    on_base = [_nodes(d, 3, tag) for tag in (caisson, mound)]
    on_base = [x[np.abs(x[:, 1] - y1) < 1e-12] for x in on_base]
    on_base[1] = on_base[1][np.abs(on_base[1][:, 0]) <= B / 2 + 1e-12]
    assert np.array_equal(on_base[0], on_base[1])
    assert len(on_base[0]) == (2 * plan.across + 1) * (2 * sum(plan.nz) + 1)
    assert np.array_equal(_nodes(d, 2, groups[goda3d.INTERFACE].tag), on_base[0])


@pytest.mark.parametrize("mesh", ["default", "wide"])
def test_named_points_are_nodes(data, mesh):
    width = L if mesh == "default" else WIDE
    expected = {
        goda3d.GAUGE_TOP: (-B / 2, H_MOUND + H - 0.041, width / 2),
        goda3d.GAUGE_BOTTOM: (-B / 2, H_MOUND + 0.041, width / 2),
        goda3d.CORNER_FRONT: (-B / 2, H_MOUND, width / 2),
        goda3d.CORNER_REAR: (B / 2, H_MOUND, width / 2),
    }
    d = data[mesh]
    geometry = goda3d.Goda3DGeometry(flume_width=None if mesh == "default" else WIDE)
    points = geometry.named_points_3d()
    assert points.keys() == expected.keys()
    for name, xyz in expected.items():
        assert points[name] == pytest.approx(xyz, rel=REL), name
        (node,) = _nodes(d, 0, d.physical_groups[name].tag)
        assert tuple(node) == pytest.approx(xyz, rel=REL), name


def test_impact_patch_and_block_position(data):
    d = data["wide"]
    groups = d.physical_groups
    x = _nodes(d, 2, groups[goda3d.IMPACT].tag)
    centre = (H_MOUND + BOLT, WIDE / 2)
    assert np.all(x[:, 0] == pytest.approx(-B / 2, rel=REL))
    for axis, c, size in ((1, centre[0], PATCH_H), (2, centre[1], PATCH_W)):
        lo, hi = x[:, axis].min(), x[:, axis].max()
        assert (lo, hi) == pytest.approx((c - size / 2, c + size / 2), rel=REL)
    z = _nodes(d, 3, groups[goda3d.CAISSON].tag)[:, 2]
    assert (z.min(), z.max()) == pytest.approx(((WIDE - L) / 2, (WIDE + L) / 2), rel=REL)
    z = _nodes(d, 2, groups[goda3d.MOUND_SIDES].tag)[:, 2]
    assert set(np.round(z, 12)) == {0.0, WIDE}


def test_refinement_scales_the_cell_count(data):
    coarse, fine = _global_cells(data["default"]), _global_cells(data["fine"])
    assert fine == goda3d.Goda3DGeometry().estimated_elements(2.0)
    # Eight times as many cells for sizes halved, less the thin layers at the patch's
    # edges and the gauge (one cell thick at both refinements): 7896 / 1032 = 7.65.
    assert 6.0 <= fine / coarse <= 8.0
    assert _global_cells(data["wide"]) == goda3d.Goda3DGeometry(
        flume_width=WIDE).estimated_elements()
    assert goda3d.Goda3DGeometry().estimated_elements(1e300) == math.inf


@pytest.mark.parametrize("slope", [0.5, 2.0, 20.0])
def test_no_inverted_or_degenerate_cells(slope):
    """gmsh's scaled Jacobian (1 for a cube, <= 0 inverted) over the straight cells."""
    with goda3d.gmsh_session():
        goda3d.build_model(goda3d.Goda3DGeometry(slope=slope), order=1)
        types, tags, _ = gmsh.model.mesh.getElements(3)
        assert [int(t) for t in types] == [5]  # 8-node hexahedra only
        quality = gmsh.model.mesh.getElementQualities(tags[0], "minSJ")
    assert quality.min() > 0.1, slope  # measured 0.57, 0.36, 0.14


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"bolt_height": 0.200}, "bolt_height"),  # the patch above the block
        ({"flume_width": 0.100}, "flume_width"),  # narrower than the block
        ({"flume_width": 0.20501}, "flume_width"),  # a sliver of free crest
        ({"flume_width": -1.0}, "flume_width"),
        ({"impact_patch_width": 0.205}, "impact_patch_width"),
        ({"caisson_length": 0.0}, "caisson_length"),
        ({"across_element_size": math.nan}, "across_element_size"),
        ({"conforming": False}, "conforming"),
        ({"caisson_width": 0.400}, "caisson_width"),
        # Node planes 0.05-0.1 mm apart (under 1e-3 of the body: needle-thin layers).
        ({"gauge_offset_top": 0.0389}, "gauge_offset_top"),  # 0.1 mm below the patch
        ({"impact_patch_width": 0.2049}, "impact_patch_width"),  # 0.05 mm from the ends
        ({"caisson_width": 0.3999}, "caisson_width"),  # 0.05 mm of crest beside it
    ],
)
def test_bad_geometry_is_refused_in_one_line(kwargs, field):
    with pytest.raises(ValueError, match=field) as error:
        goda3d.Goda3DGeometry(**kwargs)
    assert "\n" not in str(error.value)


@pytest.mark.parametrize(
    ("kwargs", "field"), [({"refinement": 0.0}, "refinement"), ({"order": 3}, "order")]
)
def test_generate_rejects_bad_arguments(shared_dir, kwargs, field):
    with pytest.raises(ValueError, match=field):
        goda3d.generate(shared_dir / "bad.msh", **kwargs)
    assert not (shared_dir / "bad.msh").exists()


def test_coarse_elements_across():
    g = goda3d.Goda3DGeometry(across_element_size=0.3)
    assert "across_element_size" in (g.coarse_elements() or "")
    assert goda3d.Goda3DGeometry().coarse_elements() is None
