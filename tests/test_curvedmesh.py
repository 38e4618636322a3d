"""Second-order (curved) geometry: meshing, the first-order warning and the outputs.

A ``.geo`` with a curved curve is meshed second order for the P2 displacement (its
mid-edge nodes on the curve) and one of straight lines first order
(:func:`breakwater.model.mesh.mesh_geo`); a first-order mesh of a curved contact
surface is warned about once (:func:`breakwater.contact.surfaces.warn_first_order`);
and the parts that read cells or facets (the general pair's surfaces, point probes,
the ParaView and snapshot writers) work on curved cells.
"""

from __future__ import annotations

import logging
import pathlib

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
import ufl
from breakwater.meshes.hertz import hertz
from dolfinx import fem

from breakwater.contact.general import SurfaceContact
from breakwater.contact.surfaces import Surface, SurfacePair, chord_sag
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, Fixed, Material
from breakwater.model.pointprobe import PointProbe
from breakwater.outputs.writers import BodyFields, FieldWriter, PairFields
from breakwater.stepping.gn22 import GN22

COMM = MPI.COMM_WORLD
R = 1.0

# A half-disc of radius R on a block (quarter model x ≥ 0), the disc's arc a circle.
HERTZ_GEO = """
h = 0.05;
Point(1) = {0, 1, 0, h}; Point(2) = {0, 0, 0, h}; Point(3) = {1, 1, 0, h};
Circle(1) = {2, 1, 3}; Line(2) = {3, 1}; Line(3) = {1, 2};
Curve Loop(1) = {1, 2, 3}; Plane Surface(1) = {1};
Point(4) = {0, -1, 0, h}; Point(5) = {2, -1, 0, h}; Point(6) = {2, 0, 0, h};
Line(4) = {4, 5}; Line(5) = {5, 6}; Line(6) = {6, 2}; Line(7) = {2, 4};
Curve Loop(2) = {4, 5, 6, 7}; Plane Surface(2) = {2};
Physical Surface("cylinder") = {1}; Physical Surface("block") = {2};
Physical Curve("cylinder_arc") = {1}; Physical Curve("block_top") = {6};
Physical Curve("block_bottom") = {4};
"""


def _area(data, name: str) -> float:  # type: ignore[no-untyped-def]
    m = ufl.Measure("dx", domain=data.mesh, subdomain_data=data.cell_tags)
    form = fem.form(fem.Constant(data.mesh, 1.0) * m(data.physical_groups[name][1]))
    return float(COMM.allreduce(fem.assemble_scalar(form), op=MPI.SUM))


def test_geo_is_meshed_second_order_where_curved(shared_dir: pathlib.Path) -> None:
    """The Hertz script: second order for P2 (the quarter disc's area πR²/4 to 1e-5:
    the arc's mid-edge nodes on the circle; measured −1.2e-8; first order: the
    chords' polygon, measured −4.0e-4); first order for P1 and for a script of straight
    lines (affine cells: the conforming pairs' compiled path)."""
    geo = shared_dir / "hertz.geo"
    if COMM.rank == 0:
        geo.write_text(HERTZ_GEO)
        (shared_dir / "blocks.geo").write_text(HERTZ_GEO.replace(
            "Circle(1) = {2, 1, 3};", "Line(1) = {2, 3};"))
    COMM.barrier()
    curved = read_mesh(geo, COMM)
    assert curved.mesh.geometry.cmaps[0].degree == 2
    assert _area(curved, "cylinder") == pytest.approx(np.pi * R**2 / 4, rel=1e-5)
    flat = read_mesh(geo, COMM, order=1)
    assert flat.mesh.geometry.cmaps[0].degree == 1
    assert abs(_area(flat, "cylinder") / (np.pi * R**2 / 4) - 1) > 1e-4
    straight = read_mesh(shared_dir / "blocks.geo", COMM)
    assert straight.mesh.geometry.cmaps[0].degree == 1


def _model(path: pathlib.Path, order: int) -> ContactModel:
    """The Hertz quarter model (meshes.hertz, element size R/50 at the contact)."""
    mesh = hertz(path, COMM, R, 3 * R, 3 * R, 0.02 * R, 0.3 * R, 0.2 * R, order=order)
    material = Material(density=2000.0, poisson=0.3, young_modulus=1e9)
    pair = SurfacePair("hertz", "cylinder", "block", "cylinder_contact", "block_top", 1e12)
    return ContactModel(read_mesh(mesh, COMM), [Body("cylinder", material),
                                                Body("block", material)],
                        surface_pairs=[pair],
                        fixed=[Fixed("block_bottom"), Fixed("block_axis", (0,)),
                               Fixed("cylinder_axis", (0,))])


def test_first_order_curved_surface_warns_once(shared_dir: pathlib.Path,
                                               caplog: pytest.LogCaptureFixture) -> None:
    """A first-order mesh of the cylinder's arc: one warning naming the pair and the
    slave surface, with the chords' largest sag h²/(8R) (measured 6.4e-4 m where the
    facets grow to 0.07 R at the arc's upper end; within 20 %); none for
    the flat master, none for a second stepper of the same model (an adaptive level,
    a second run), none on the second-order mesh.

    A second model (a case built again, a study's next case, in the same process) is
    warned about again: once per process, a notebook's or a study's second case
    said nothing of its own first-order mesh (sweep.csv listed it for the first case
    only)."""
    for order, expected in ((1, 1), (1, 1), (2, 0)):
        model = _model(shared_dir / f"hertz{order}.msh", order)
        with caplog.at_level(logging.WARNING, logger="breakwater.contact.surfaces"):
            caplog.clear()
            stepper = GN22(model, 1e-3)
            stepper.initialise()
            provider = stepper.surfaces[-1]
            assert isinstance(provider, SurfaceContact)
            again = GN22(model, 5e-4)  # the same model: not warned again
            again.initialise()
            again.destroy()
            warned = [r.getMessage() for r in caplog.records if "first order" in r.getMessage()]
        if COMM.rank == 0:
            assert len(warned) == expected, warned
            if expected:
                assert "contact 'hertz': surface 'cylinder_contact' is curved" in warned[0]
                assert "second order" in warned[0]
        if order == 1:
            n, _, sag = chord_sag(provider.slave)
            assert n > 10
            chords = provider.slave.X[:, 1] - provider.slave.X[:, 0]
            h = np.linalg.norm(chords, axis=1).max()  # the arc's coarse end
            assert sag == pytest.approx(h**2 / (8 * R), rel=0.2)
            assert chord_sag(provider.master)[0] == 0
        stepper.destroy()


def test_outputs_on_curved_cells(shared_dir: pathlib.Path) -> None:
    """On the second-order Hertz mesh: the slave surface's mid-edge nodes on the
    circle (1e-12), a point probe inside a curved cell between its chord and the arc
    (the interpolated u = x there: its coordinates to 1e-12), and the ParaView body
    and contact fields and the snapshots' nodal arrays written."""
    model = _model(shared_dir / "hertz.msh", 2)
    stepper = GN22(model, 1e-3)
    stepper.initialise()
    provider = stepper.surfaces[-1]
    assert isinstance(provider, SurfaceContact)
    X = provider.slave.X
    np.testing.assert_allclose(np.linalg.norm(X - [0.0, R], axis=2), R, rtol=1e-12)
    # A point between the chord and the arc of the facet at 10°.
    θ = np.radians(10.0)
    point = (R * np.sin(θ) * (1 - 1e-6), R - R * np.cos(θ) * (1 - 1e-6))
    probe = PointProbe(model, "cylinder", point)
    for f in stepper.u:
        f.interpolate(lambda x: x[:2])
    np.testing.assert_allclose(probe.value(stepper.u), point, rtol=1e-12)
    body = [BodyFields(model, i) for i in range(len(model.bodies))]
    pair = [PairFields(model, p) for p in stepper.contacts if p.name == "hertz"]
    writer = FieldWriter(body, pair, shared_dir, COMM)
    writer.write(0.0, stepper.u, stepper.v)
    writer.close()
    for f in body:
        nodal = f.nodal()
        if COMM.rank == 0:
            assert nodal is not None and np.all(np.isfinite(nodal["ux"]))
    assert all(p.exists() for p in writer.paths)
    stepper.destroy()


def _two_triangles(path: pathlib.Path, mid: tuple[float, float]) -> pathlib.Path:
    """Two six-node triangles of the unit square, the first's mid-node of its edge
    (0,0)-(1,0) at ``mid`` (rank 0 writes)."""
    import gmsh

    from breakwater.common.gmshtools import gmsh_session
    from breakwater.common.parallel import on_rank_zero

    def write() -> str:
        with gmsh_session(model="curved"):
            surface = gmsh.model.addDiscreteEntity(2)
            xy = [(0, 0), (1, 0), (1, 1), (0, 1), mid, (1, 0.5), (0.5, 0.5), (0.5, 1),
                  (0, 0.5)]
            gmsh.model.mesh.addNodes(2, surface, list(range(1, 10)),
                                     [c for x, y in xy for c in (x, y, 0.0)])
            # (0,0) (1,0) (1,1) | mids 5 6 7; (0,0) (1,1) (0,1) | mids 7 8 9.
            gmsh.model.mesh.addElementsByType(surface, 9, [1, 2],
                                              [1, 2, 3, 5, 6, 7, 1, 3, 4, 7, 8, 9])
            gmsh.model.addPhysicalGroup(2, [surface], name="square")
            gmsh.write(str(path))
        return str(path)

    return pathlib.Path(on_rank_zero(COMM, write))


def test_folded_curved_cell_is_refused(shared_dir: pathlib.Path) -> None:
    """A six-node triangle whose mid-edge node is pushed across the cell (its
    Jacobian changes sign) is refused in one line naming the cell; moved a quarter
    of the way in, it is a valid curved cell (its Jacobian at the nodes half the
    straight cell's or more: measured 0.5)."""
    from breakwater.common.errors import MeshError
    from breakwater.model.mesh import curved_jacobian

    ok = read_mesh(_two_triangles(shared_dir / "ok.msh", (0.5, 0.125)), COMM)
    assert ok.mesh.geometry.cmaps[0].degree == 2
    x = np.array([[(0, 0), (1, 0), (1, 1), (0.5, 0.125), (1, 0.5), (0.5, 0.5)]], float)
    assert curved_jacobian(x)[0] == pytest.approx(0.5)
    x[0, 3] = (0.5, 0.0)
    assert curved_jacobian(x)[0] == pytest.approx(1.0)
    with pytest.raises(MeshError, match=r"folded.msh: curved cell 1 at .* folds"):
        read_mesh(_two_triangles(shared_dir / "folded.msh", (0.5, 0.45)), COMM)


def test_case_geo_is_meshed_to_the_displacement_degree(shared_dir: pathlib.Path) -> None:
    """A case's ``mesh.source`` ``.geo`` with a circle arc: second-order cells with
    ``mesh.degree = 2`` (the default), first-order with ``mesh.degree = 1``."""
    import tomli_w

    from breakwater.casefile.case import load_case

    geo = shared_dir / "hertz.geo"
    for degree in (2, 1):
        toml = shared_dir / f"hertz{degree}.toml"
        if COMM.rank == 0:
            geo.write_text(HERTZ_GEO)
            toml.write_text(tomli_w.dumps({
                "mesh": {"source": "hertz.geo", "degree": degree},
                "bodies": {b: {"density": 2000.0, "poisson": 0.3, "shear_modulus": 4e8}
                           for b in ("cylinder", "block")},
                "contact": {"hertz": {"slave": "cylinder", "master": "block",
                                      "slave_surface": "cylinder_arc",
                                      "master_surface": "block_top", "penalty": 1e12}},
                "fixed": {"block_bottom": {}},
                "time": {"dt": 1e-4, "end_time": 1e-3},
                "output": {"directory": str(shared_dir / f"out{degree}")}}))
        COMM.barrier()
        data = load_case(toml).read_mesh(COMM)
        assert data.mesh.geometry.cmaps[0].degree == degree


def _polyline(points: np.ndarray) -> Surface:
    """A surface of P2 facets along a polyline (mid-edge nodes on the chords)."""
    a, b = points[:-1], points[1:]
    X = np.stack([a, b, 0.5 * (a + b)], axis=1)
    ids = np.arange(len(points))
    vertex = np.stack([ids[:-1], ids[1:], len(points) + ids[:-1]], axis=1)
    dofs = np.stack([2 * vertex, 2 * vertex + 1], axis=2)
    return Surface(X, dofs, 0.5 * (a + b) - [0.0, 0.1])


def test_corners_are_not_a_curve() -> None:
    """A first-order soil surface with a notch one facet wide and deep (four right
    angles in a row) is no curve: before, it was warned about as "curved (its facets
    turn by up to 90° at 4 nodes) ... up to 8.7e-02 m inside the curve" (an L-shaped
    wall's shear key, on the user path). A circle in 12 facets (30° turns) still is."""
    notch = np.array([[-1.5, 0], [-0.2, 0], [-0.2, -0.4], [0.2, -0.4], [0.2, 0], [1.5, 0]])
    assert chord_sag(_polyline(notch))[0] == 0
    angle = np.linspace(np.pi, 2 * np.pi, 7)  # a half circle of 6 facets: 30° turns
    n, turn, sag = chord_sag(_polyline(np.stack([np.cos(angle), np.sin(angle)], axis=1)))
    assert n == 5 and turn == pytest.approx(np.pi / 6)
    h = 2 * np.sin(np.pi / 12)
    assert sag == pytest.approx(h**2 / 8, rel=0.02)  # h²/(8R), R = 1 (the chord as arc: 1 %)
