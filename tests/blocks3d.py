"""Two stacked blocks in 2D (quadrilaterals) and in 3D (their extrusion), for the 3D tests.

Body ``a`` (the slave) of ``a = (width, height)`` sits centred on body ``b`` of the same
width; they share one conforming interface. The 2D mesh is structured quadrilaterals
(Q2 after ``setOrder(2)``); :func:`block_pair` with ``thickness`` extrudes the same 2D
mesh along z over ``layers`` hexahedra (Q2, 27 nodes), so that every 3D node column
lies over a 2D node: the plane-strain slab of the 2D model. ``tetrahedra=True`` meshes
the same boxes with quadratic tetrahedra instead (unstructured).

Physical names (as :mod:`blocks`): ``a``, ``b`` (cells); ``interface``; ``a_top``,
``a_left``, ``a_right``, ``b_bottom``, ``b_left``, ``b_right``; in 3D also ``a_sides``,
``b_sides`` (the faces z = 0 and z = thickness). Points: ``a_corner`` (the lower-left
corner of ``a``; in 3D at z = 0).
"""

from __future__ import annotations

import pathlib

import gmsh
from breakwater.meshes import gmsh_session
from mpi4py import MPI

from breakwater.common.parallel import on_rank_zero


def block_pair(path: str | pathlib.Path, comm: MPI.Comm, width: float,
               heights: tuple[float, float], h: float, thickness: float | None = None,
               layers: int = 1, tetrahedra: bool = False) -> pathlib.Path:
    """Write the mesh of block ``a`` on block ``b``; quadratic cells.

    Args:
        path: Output ``.msh`` (the same on every rank).
        comm: Communicator (rank 0 writes).
        width: Both blocks' width (x), centred on x = 0.
        heights: ``(a, b)`` heights (y); ``b`` from y = 0, ``a`` on top.
        h: Element size.
        thickness: None: 2D quadrilaterals; else the extrusion along z (m).
        layers: Hexahedra across the thickness.
        tetrahedra: 3D only: quadratic tetrahedra (gmsh's unstructured mesher) instead
            of the extruded hexahedra.
    """
    path = pathlib.Path(path)
    ha, hb = heights

    def build() -> None:
        with gmsh_session():
            geo = gmsh.model.geo
            x0, x1 = -width / 2, width / 2
            p = [geo.addPoint(x, y, 0, h) for x, y in
                 ((x0, 0), (x1, 0), (x1, hb), (x0, hb), (x1, hb + ha), (x0, hb + ha))]
            bb, br, itf, bl = (geo.addLine(p[0], p[1]), geo.addLine(p[1], p[2]),
                               geo.addLine(p[2], p[3]), geo.addLine(p[3], p[0]))
            ar, at, al = geo.addLine(p[2], p[4]), geo.addLine(p[4], p[5]), geo.addLine(p[5], p[3])
            sb = geo.addPlaneSurface([geo.addCurveLoop([bb, br, itf, bl])])
            sa = geo.addPlaneSurface([geo.addCurveLoop([-itf, ar, at, al])])
            nx = max(1, round(width / h)) + 1
            if not tetrahedra:
                for c in (bb, itf, at):
                    geo.mesh.setTransfiniteCurve(c, nx)
                for c, L in ((br, hb), (bl, hb), (ar, ha), (al, ha)):
                    geo.mesh.setTransfiniteCurve(c, max(1, round(L / h)) + 1)
                for s in (sa, sb):
                    geo.mesh.setTransfiniteSurface(s)
                    geo.mesh.setRecombine(2, s)
            curves = {"interface": [itf], "a_top": [at], "a_left": [al], "a_right": [ar],
                      "b_bottom": [bb], "b_left": [bl], "b_right": [br]}
            if thickness is None:
                geo.synchronize()
                gmsh.model.addPhysicalGroup(2, [sa], name="a")
                gmsh.model.addPhysicalGroup(2, [sb], name="b")
                for name, tags in curves.items():
                    gmsh.model.addPhysicalGroup(1, tags, name=name)
                gmsh.model.addPhysicalGroup(0, [p[3]], name="a_corner")
                gmsh.model.mesh.generate(2)
            else:
                # Extruding a surface gives [its copy at z = thickness, the volume, the
                # lateral surfaces in the order of its curves]; the two blocks in one
                # call, so that the interface's extrusion is one surface of both.
                out = geo.extrude([(2, sa), (2, sb)], 0, 0, thickness,
                                  numElements=[] if tetrahedra else [layers],
                                  recombine=not tetrahedra)
                loop = {"a": [itf, ar, at, al], "b": [bb, br, itf, bl]}
                lateral: dict[int, set[int]] = {}
                sides, volumes, k = {"a": [sa], "b": [sb]}, {}, 0
                for name in ("a", "b"):
                    sides[name].append(out[k][1])
                    volumes[name] = out[k + 1][1]
                    for c, (_, f) in zip(loop[name], out[k + 2:k + 6], strict=True):
                        lateral.setdefault(c, set()).add(f)
                    k += 6
                geo.synchronize()
                gmsh.model.addPhysicalGroup(3, [volumes["a"]], name="a")
                gmsh.model.addPhysicalGroup(3, [volumes["b"]], name="b")
                for name, (c,) in curves.items():
                    gmsh.model.addPhysicalGroup(2, sorted(lateral[c]), name=name)
                gmsh.model.addPhysicalGroup(2, sides["a"], name="a_sides")
                gmsh.model.addPhysicalGroup(2, sides["b"], name="b_sides")
                gmsh.model.addPhysicalGroup(0, [p[3]], name="a_corner")
                gmsh.model.mesh.generate(3)
            gmsh.model.mesh.setOrder(2)
            gmsh.write(str(path))

    on_rank_zero(comm, build)
    return pathlib.Path(comm.bcast(str(path), root=0))


def interface_values(stepper, field: str = "u") -> tuple:
    """A GN22 stepper's first conforming pair: its nodes' coordinates, the slave's and
    the master's values of ``field`` ("u", "v" or "a") there (gathered, every rank)."""
    f = getattr(stepper, field)
    nodes = stepper.nodes[0]
    s, m = nodes.gather(f[0].x.array, f[1].x.array)
    return nodes.x, s, m


def slab_against_2d(two, three, steps: int) -> tuple[dict[str, float], float]:
    """Step a plane-strain model and its 3D slab together, comparing their interfaces.

    Every 3D interface node lies over a 2D one (the 3D values at each z). After each
    step, the largest difference of u and v between them, and the largest |u_z|,
    relative to the 2D slave side's largest |u| (|v|).

    Returns:
        The worst relative differences over the steps (``u``, ``v``, ``u_z``) and the
        2D interface's mean slide (slave minus master u_x) at the end.
    """
    import numpy as np

    x2, x3 = interface_values(two)[0], interface_values(three)[0]
    index = [int(np.argmin(np.linalg.norm(x2 - p[:2], axis=1))) for p in x3]
    assert np.allclose(x2[index], x3[:, :2], atol=1e-12)
    worst = {"u": 0.0, "v": 0.0, "u_z": 0.0}
    slide = 0.0
    for _ in range(steps):
        two.step()
        three.step()
        for field in ("u", "v"):
            _, s2, m2 = interface_values(two, field)
            _, s3, m3 = interface_values(three, field)
            scale = max(np.abs(s2).max(), 1e-300)
            worst[field] = max(worst[field], np.abs(s3[:, :2] - s2[index]).max() / scale,
                               np.abs(m3[:, :2] - m2[index]).max() / scale)
            if field == "u":
                worst["u_z"] = max(worst["u_z"], np.abs(s3[:, 2]).max() / scale)
                slide = float(np.mean(s2[:, 0] - m2[:, 0]))
    return worst, slide
