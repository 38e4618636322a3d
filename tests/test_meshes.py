"""Tests of the parametric Goda (1994) mesh and its export (serial and under MPI)."""

from __future__ import annotations

import math
import pathlib
import signal
import sys
from typing import Any

import gmsh
import numpy as np
import pytest
from mpi4py import MPI

try:
    from breakwater.meshes import export, goda
except ImportError:  # running from a source checkout without installation
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
    from meshes import export, goda  # type: ignore[no-redef]

import dolfinx_solver  # noqa: F401, I001  (must precede dolfinx)
import dolfinx

COMM = MPI.COMM_WORLD

# Reference values from the geometry formulas of Goda's model (metres).
H_MOUND, CREST, SLOPE = 0.190, 0.400, 2.0
B_CAISSON, H_CAISSON = 0.205, 0.202
BASE_WIDTH = CREST + 2 * SLOPE * H_MOUND
CAISSON_AREA = B_CAISSON * H_CAISSON
MOUND_AREA = 0.5 * (CREST + BASE_WIDTH) * H_MOUND
PAPER_TRIANGLES = {goda.CAISSON: 156, goda.MOUND: 558}


@pytest.fixture(scope="module")
def meshes(folder: pathlib.Path) -> dict[float, pathlib.Path]:
    """Goda's mesh at refinements 1 and 2 (order 1)."""
    return {
        r: goda.generate(folder / f"goda_r{r:g}.msh", refinement=r) for r in (1.0, 2.0)
    }


def _cells(mesh, name: str) -> np.ndarray:
    """Connectivity of the cells of physical group `name` (corner nodes first)."""
    dim, tag = {**goda.PHYSICAL_GROUPS, **goda.SEPARATE_PHYSICAL_GROUPS}[name]
    blocks = [
        block.data[phys == tag]
        for block, phys in zip(mesh.cells, mesh.cell_data["gmsh:physical"], strict=True)
        if block.dim == dim
    ]
    return np.concatenate(blocks)


def _area(mesh, name: str) -> float:
    x = mesh.points[_cells(mesh, name)[:, :3], :2]
    d1, d2 = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]
    return float(np.sum(0.5 * (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])))


def _length(mesh, name: str) -> float:
    x = mesh.points[_cells(mesh, name)[:, :2], :2]
    return float(np.linalg.norm(x[:, 1] - x[:, 0], axis=1).sum())


def _read_from_msh(path: pathlib.Path, **kwargs: Any) -> Any:
    """dolfinx's ``read_from_msh`` (gdim 2) with SIGINT's handler kept.

    Its ``gmsh.initialize()`` (interruptible, on rank 0) sets SIGINT to the default
    action, and gmsh 4.15's ``finalize`` does not put it back (``initialize`` keeps the
    previous handler in a local variable): every later test ran with Ctrl-C killing the
    process (test_signals' interactive test saw it first).
    """
    previous = signal.getsignal(signal.SIGINT)
    try:
        return dolfinx.io.gmsh.read_from_msh(path, COMM, 0, gdim=2, **kwargs)
    finally:
        signal.signal(signal.SIGINT, previous)


def test_physical_groups_present_with_dimensions(meshes):
    mesh = export.read(meshes[1.0])
    found = {name: (int(dim), int(tag)) for name, (tag, dim) in mesh.field_data.items()}
    assert found == dict(goda.PHYSICAL_GROUPS)
    for name in goda.PHYSICAL_GROUPS:
        assert len(_cells(mesh, name)) > 0, name
    assert {goda.CAISSON, goda.MOUND} == {n for n, (d, _) in found.items() if d == 2}


def test_triangle_counts_match_paper_and_scale_with_refinement(meshes):
    coarse, fine = export.read(meshes[1.0]), export.read(meshes[2.0])
    for name, paper in PAPER_TRIANGLES.items():
        n1, n2 = len(_cells(coarse, name)), len(_cells(fine, name))
        assert abs(n1 - paper) <= 0.1 * paper, (name, n1)
        assert 3.0 <= n2 / n1 <= 5.0, (name, n1, n2)


@pytest.mark.parametrize("refinement", [1.0, 2.0])
def test_areas_and_lengths(meshes, refinement):
    mesh = export.read(meshes[refinement])
    assert _area(mesh, goda.CAISSON) == pytest.approx(CAISSON_AREA, rel=1e-12)
    assert _area(mesh, goda.MOUND) == pytest.approx(MOUND_AREA, rel=1e-12)
    slope_length = H_MOUND * math.hypot(1.0, SLOPE)
    expected = {
        goda.INTERFACE: B_CAISSON,
        goda.BASE: BASE_WIDTH,
        goda.IMPACT: 0.010,
        goda.CAISSON_FRONT: H_CAISSON - 0.010,
        goda.CAISSON_REAR: H_CAISSON,
        goda.CAISSON_TOP: B_CAISSON,
        goda.MOUND_SURFACE: CREST - B_CAISSON + 2 * slope_length,
    }
    for name, length in expected.items():
        assert _length(mesh, name) == pytest.approx(length, rel=1e-12), name
    y = mesh.points[_cells(mesh, goda.IMPACT)][..., 1]
    assert (y.min(), y.max()) == pytest.approx(
        (H_MOUND + 0.163, H_MOUND + 0.173), rel=1e-12
    )


def test_named_points(meshes):
    expected = {
        goda.GAUGE_TOP: (-B_CAISSON / 2, H_MOUND + H_CAISSON - 0.041),
        goda.GAUGE_BOTTOM: (-B_CAISSON / 2, H_MOUND + 0.041),
        goda.CORNER_FRONT: (-B_CAISSON / 2, H_MOUND),
        goda.CORNER_REAR: (B_CAISSON / 2, H_MOUND),
    }
    geometry = goda.GodaGeometry()
    points = geometry.named_points()
    assert points.keys() == expected.keys()
    for name, xy in expected.items():
        assert points[name] == pytest.approx(xy, rel=1e-12), name
    assert geometry.impact_point == pytest.approx(
        (-B_CAISSON / 2, H_MOUND + 0.168), rel=1e-12
    )
    mesh = export.read(meshes[1.0])
    for name, xy in expected.items():
        (node,) = _cells(mesh, name).ravel()
        assert tuple(mesh.points[node, :2]) == pytest.approx(xy, rel=1e-12), name


def test_interface_conforming_in_dolfinx(meshes):
    lines = len(_cells(export.read(meshes[1.0]), goda.INTERFACE))
    partitioner = dolfinx.mesh.create_cell_partitioner(
        dolfinx.mesh.GhostMode.shared_facet, 2
    )
    data = _read_from_msh(meshes[1.0], partitioner=partitioner)
    assert data.physical_groups == dict(goda.PHYSICAL_GROUPS)
    mesh, topology = data.mesh, data.mesh.topology
    topology.create_connectivity(1, 2)
    facet_to_cell = topology.connectivity(1, 2)
    num_cells = topology.index_map(2).size_local + topology.index_map(2).num_ghosts
    cell_value = np.full(num_cells, -1)
    cell_value[data.cell_tags.indices] = data.cell_tags.values
    bodies = sorted(data.physical_groups[n].tag for n in (goda.CAISSON, goda.MOUND))

    facets = data.facet_tags.find(data.physical_groups[goda.INTERFACE].tag)
    owned = facets[facets < topology.index_map(1).size_local]
    for facet in owned:
        assert sorted(cell_value[facet_to_cell.links(facet)]) == bodies
    assert COMM.allreduce(len(owned)) == lines

    # Points (dim 0) come as ridge tags, i.e. vertex tags in 2D.
    ridges = data.ridge_tags
    assert ridges is not None and ridges.dim == 0
    nodes = dolfinx.mesh.entities_to_geometry(mesh, 0, ridges.indices).ravel()
    local = {
        int(v): tuple(mesh.geometry.x[n, :2])
        for v, n in zip(ridges.values, nodes, strict=True)
    }
    found = {k: v for d in COMM.allgather(local) for k, v in d.items()}
    for name, xy in goda.GodaGeometry().named_points().items():
        assert found[goda.PHYSICAL_GROUPS[name][1]] == pytest.approx(xy, rel=1e-12), (
            name
        )


def test_second_order(shared_dir):
    path = goda.generate(shared_dir / "goda_p2.msh", order=2)
    mesh = export.read(path)
    assert {b.type for b in mesh.cells} == {"triangle6", "line3", "vertex"}
    assert len(_cells(mesh, goda.CAISSON)) == len(_cells(mesh, goda.CAISSON)[:, :3])
    assert _area(mesh, goda.CAISSON) == pytest.approx(CAISSON_AREA, rel=1e-12)
    assert _area(mesh, goda.MOUND) == pytest.approx(MOUND_AREA, rel=1e-12)
    data = _read_from_msh(path)
    assert data.mesh.geometry.cmaps[0].degree == 2
    cells = data.mesh.topology.index_map(2).size_global
    assert cells == sum(len(_cells(mesh, n)) for n in PAPER_TRIANGLES)


@pytest.mark.parametrize("offset_top", [H_CAISSON - 0.168, H_CAISSON - 0.163])
def test_gauge_on_impact_patch(shared_dir, offset_top):
    """A gauge inside the patch (or on its end) splits it but keeps it whole."""
    geometry = goda.GodaGeometry(gauge_offset_top=offset_top)
    mesh = export.read(goda.generate(shared_dir / "gauge.msh", geometry))
    assert _length(mesh, goda.IMPACT) == pytest.approx(0.010, rel=1e-12)
    assert _length(mesh, goda.CAISSON_FRONT) == pytest.approx(
        H_CAISSON - 0.010, rel=1e-12
    )
    (node,) = _cells(mesh, goda.GAUGE_TOP).ravel()
    assert tuple(mesh.points[node, :2]) == pytest.approx(geometry.gauge_top, rel=1e-12)


def _group_cells(mesh, name: str) -> set[tuple[int, ...]]:
    return {tuple(sorted(c)) for c in _cells(mesh, name).tolist()}


@pytest.mark.parametrize("suffix", [".vtu", ".msh"])  # .xdmf: breakwater's (test_xdmfmesh)
def test_export_round_trip(meshes, shared_dir, suffix):
    original = export.read(meshes[1.0])
    copy = export.read(export.convert(meshes[1.0], shared_dir / f"goda{suffix}"))
    np.testing.assert_array_equal(copy.points[:, :2], original.points[:, :2])
    for name in goda.PHYSICAL_GROUPS:
        assert _group_cells(copy, name) == _group_cells(original, name), name


def test_export_unknown_suffix(meshes, shared_dir):
    with pytest.raises(ValueError, match=r"suffix '\.foo'"):
        export.convert(meshes[1.0], shared_dir / "goda.foo")


def test_export_failure_raises_on_all_ranks(shared_dir):
    with pytest.raises(Exception, match="not found"):
        export.convert(shared_dir / "missing.msh", shared_dir / "missing.vtu")


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("mound_height", 0.0),
        ("slope", math.nan),
        ("caisson_width", 0.400),
        ("caisson_height", -0.2),
        ("bolt_height", 0.200),
        ("bolt_height", 0.004),
        ("impact_patch_height", 0.0),
        ("gauge_offset_top", 0.202),
        ("gauge_offset_bottom", 0.3),
        ("caisson_element_size", math.inf),
    ],
)
def test_validation_names_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        goda.GodaGeometry(**{field: value})


@pytest.mark.parametrize(
    ("kwargs", "field"), [({"refinement": 0.0}, "refinement"), ({"order": 3}, "order")]
)
def test_generate_rejects_bad_arguments(shared_dir, kwargs, field):
    with pytest.raises(ValueError, match=field):
        goda.generate(shared_dir / "bad.msh", **kwargs)
    assert not (shared_dir / "bad.msh").exists()


def test_existing_gmsh_session_is_left_alone(shared_dir):
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("outer")
        gmsh.model.geo.addPoint(1.0, 2.0, 0.0)
        gmsh.model.geo.synchronize()
        gmsh.option.setNumber("Mesh.Algorithm", 5)
        goda.generate(shared_dir / "inside.msh")
        assert gmsh.isInitialized()
        assert gmsh.model.getCurrent() == "outer"
        assert gmsh.model.getEntities() == [(0, 1)]
        assert gmsh.option.getNumber("Mesh.Algorithm") == 5
    finally:
        gmsh.finalize()
    assert (shared_dir / "inside.msh").exists()


def test_gmsh_session_finalises_on_errors():
    from breakwater.common.gmshtools import gmsh_session

    assert not gmsh.isInitialized()
    with pytest.raises(ZeroDivisionError), gmsh_session({"Mesh.Algorithm": 5}):
        assert gmsh.isInitialized() and gmsh.option.getNumber("Mesh.Algorithm") == 5
        assert gmsh.option.getNumber("General.Terminal") == 0  # the default: quiet
        1 / 0  # noqa: B018
    assert not gmsh.isInitialized()


# --- the separately meshed model (conforming = False) ---------------------------------

# The caisson finer than the mound, in the ratio of the example
# (examples/goda_nonmatching.toml): 0.0265 / 0.0156 = 1.70.
SEPARATE = goda.GodaGeometry(conforming=False, caisson_element_size=0.0156)


@pytest.fixture(scope="module")
def separate(folder: pathlib.Path) -> pathlib.Path:
    """The separately meshed model (order 2, as the runs use it)."""
    return goda.generate(folder / "goda_separate.msh", SEPARATE, order=2)


def _nodes(mesh, name: str) -> set[int]:
    return set(_cells(mesh, name).ravel().tolist())


def test_separate_groups_present(separate):
    mesh = export.read(separate)
    found = {name: (int(dim), int(tag)) for name, (tag, dim) in mesh.field_data.items()}
    assert found == dict(goda.SEPARATE_PHYSICAL_GROUPS) == dict(SEPARATE.physical_groups)
    assert goda.INTERFACE not in found
    assert found.keys() == set(goda.PHYSICAL_GROUPS) - {goda.INTERFACE} | {
        goda.CAISSON_BASE, goda.MOUND_CREST}
    for name in found:
        assert len(_cells(mesh, name)) > 0, name
    # New tags are not reused from the conforming model (files without names decode).
    assert not {t for _, t in found.values()} & {
        goda.PHYSICAL_GROUPS[goda.INTERFACE][1]}


def test_separate_bodies_share_no_node(separate):
    mesh = export.read(separate)
    caisson, mound = _nodes(mesh, goda.CAISSON), _nodes(mesh, goda.MOUND)
    assert not caisson & mound
    # Each group is on its body: facets on the caisson or the mound, points on the caisson.
    on_caisson = (goda.CAISSON_BASE, goda.IMPACT, goda.CAISSON_FRONT, goda.CAISSON_REAR,
                  goda.CAISSON_TOP, goda.GAUGE_TOP, goda.GAUGE_BOTTOM, goda.CORNER_FRONT,
                  goda.CORNER_REAR)
    for name in on_caisson:
        assert _nodes(mesh, name) <= caisson, name
    for name in (goda.MOUND_CREST, goda.MOUND_SURFACE, goda.BASE):
        assert _nodes(mesh, name) <= mound, name
    # The caisson base and the crest coincide in space (y = mound height) ...
    base = mesh.points[sorted(_nodes(mesh, goda.CAISSON_BASE)), :2]
    crest = mesh.points[sorted(_nodes(mesh, goda.MOUND_CREST)), :2]
    assert np.abs(base[:, 1] - H_MOUND).max() < 1e-15
    assert np.abs(crest[:, 1] - H_MOUND).max() < 1e-15
    assert (base[:, 0].min(), base[:, 0].max()) == pytest.approx(
        (-B_CAISSON / 2, B_CAISSON / 2), rel=1e-12)
    assert (crest[:, 0].min(), crest[:, 0].max()) == pytest.approx(
        (-CREST / 2, CREST / 2), rel=1e-12)
    # ... but do not match: of the crest nodes under the caisson only the middle one
    # (x = 0, both curves being divided evenly and symmetrically) is at a base node.
    x_base, x_crest = base[:, 0], crest[:, 0]
    nearest = np.abs(x_crest[:, None] - x_base[None, :]).min(axis=1)
    under = np.abs(x_crest) < B_CAISSON / 2
    assert under.sum() > 10
    assert np.count_nonzero(nearest[under] < 1e-6) == 1


def test_separate_areas_and_lengths_equal_the_conforming(meshes, separate):
    conforming, mesh = export.read(meshes[1.0]), export.read(separate)
    for name in (goda.CAISSON, goda.MOUND):
        assert _area(mesh, name) == pytest.approx(_area(conforming, name), rel=1e-12)
    for name in (goda.BASE, goda.IMPACT, goda.CAISSON_FRONT, goda.CAISSON_REAR,
                 goda.CAISSON_TOP):
        assert _length(mesh, name) == pytest.approx(_length(conforming, name), rel=1e-12)
    assert _length(mesh, goda.CAISSON_BASE) == pytest.approx(
        _length(conforming, goda.INTERFACE), rel=1e-12)
    # The crest is whole (under the caisson and beside it); the slopes are the rest.
    slopes = 2 * H_MOUND * math.hypot(1.0, SLOPE)
    assert _length(mesh, goda.MOUND_CREST) == pytest.approx(CREST, rel=1e-12)
    assert _length(mesh, goda.MOUND_SURFACE) == pytest.approx(slopes, rel=1e-12)
    assert _length(mesh, goda.MOUND_CREST) + _length(mesh, goda.MOUND_SURFACE) == (
        pytest.approx(_length(conforming, goda.INTERFACE)
                      + _length(conforming, goda.MOUND_SURFACE), rel=1e-12))
    for name, xy in SEPARATE.named_points().items():
        (node,) = _cells(mesh, name).ravel()
        assert tuple(mesh.points[node, :2]) == pytest.approx(xy, rel=1e-12), name


def test_separate_element_sizes_independent(separate):
    # Mean segment lengths of the two contact curves: the sizes asked (the curves are
    # divided evenly; ceil(length / size) segments), ratio 1.7 as the geometry's sizes.
    mesh = export.read(separate)
    n_base = len(_cells(mesh, goda.CAISSON_BASE))
    n_crest = len(_cells(mesh, goda.MOUND_CREST))
    assert n_base == math.ceil(B_CAISSON / SEPARATE.caisson_element_size)
    assert n_crest == math.ceil(CREST / SEPARATE.mound_element_size)
    ratio = (CREST / n_crest) / (B_CAISSON / n_base)
    assert ratio == pytest.approx(SEPARATE.mound_element_size
                                  / SEPARATE.caisson_element_size, rel=0.1)


def test_separate_in_dolfinx(separate):
    # Every facet of caisson_base / mound_crest is on the boundary of its own body only.
    data = _read_from_msh(separate)
    assert data.physical_groups == dict(goda.SEPARATE_PHYSICAL_GROUPS)
    topology = data.mesh.topology
    topology.create_connectivity(1, 2)
    facet_to_cell = topology.connectivity(1, 2)
    imap = topology.index_map(2)
    cell_value = np.full(imap.size_local + imap.num_ghosts, -1)
    cell_value[data.cell_tags.indices] = data.cell_tags.values
    for group, body in ((goda.CAISSON_BASE, goda.CAISSON), (goda.MOUND_CREST, goda.MOUND)):
        facets = data.facet_tags.find(data.physical_groups[group].tag)
        owned = facets[facets < topology.index_map(1).size_local]
        for facet in owned:
            assert list(cell_value[facet_to_cell.links(facet)]) == [
                data.physical_groups[body].tag], group
        lines = len(_cells(export.read(separate), group))
        assert COMM.allreduce(len(owned)) == lines


def test_conforming_is_a_bool():
    with pytest.raises(ValueError, match="conforming"):
        goda.GodaGeometry(conforming=1)  # type: ignore[arg-type]
