"""Two-rectangle gmsh meshes for the verification tests.

Body ``a`` (the slave in the tests) sits on top of body ``b`` (``layout="stacked"``)
or to the left of it (``layout="side"``); they share one conforming interface curve.
Physical names: ``a``, ``b`` (cells); ``interface``; ``a_top``, ``a_left``,
``a_right``, ``a_bottom_free``; ``b_bottom``, ``b_left``, ``b_right``, ``b_top_free``
(facets; free parts exist only when the widths differ). Points: ``a_corner`` (the
lower-left corner of ``a``). :func:`two_block_case` is the case file of such a mesh.
:func:`stacked_blocks` meshes rectangles stacked bottom up; :func:`three_blocks` is the
model of three of them that several tests share.
"""

from __future__ import annotations

import math
import pathlib
from collections.abc import Callable
from typing import Any

import gmsh
import pytest
from breakwater.meshes import gmsh_session
from mpi4py import MPI

from breakwater.common.parallel import on_rank_zero
from breakwater.model.mesh import read_mesh
from breakwater.model.model import (
    Body,
    ContactModel,
    ContactPair,
    Damping,
    Fixed,
    Material,
    SurfaceLoad,
)
from breakwater.stepping.gn22 import GN22


def two_rectangles(path: str | pathlib.Path, comm: MPI.Comm, a: tuple[float, float],
                   b: tuple[float, float], h: float, layout: str = "stacked",
                   structured: bool = True) -> pathlib.Path:
    """Write a mesh of two rectangles sharing a conforming interface.

    Args:
        path: Output ``.msh`` (must be the same on all ranks of ``comm``).
        comm: Communicator (rank 0 writes).
        a: (width, height) of body ``a``.
        b: (width, height) of body ``b``.
        h: Element size.
        layout: ``"stacked"`` (a centred on top of b; interface horizontal at y = b_h)
            or ``"side"`` (a left of b, same height; interface vertical at x = 0).
        structured: Transfinite (structured) triangles, when the shapes allow it.
    """
    path = pathlib.Path(path)

    def build() -> None:
        with gmsh_session():
            geo = gmsh.model.geo
            (aw, ah), (bw, bh) = a, b
            if layout == "stacked":
                # b: [-bw/2, bw/2] x [0, bh]; a: [-aw/2, aw/2] x [bh, bh + ah]
                xs = sorted({-bw / 2, -aw / 2, aw / 2, bw / 2})
                pb = [geo.addPoint(x, bh, 0, h) for x in xs]
                b0, b1 = geo.addPoint(-bw / 2, 0, 0, h), geo.addPoint(bw / 2, 0, 0, h)
                a0, a1 = geo.addPoint(-aw / 2, bh + ah, 0, h), geo.addPoint(aw / 2, bh + ah, 0, h)
                top_b = [geo.addLine(pb[i], pb[i + 1]) for i in range(len(pb) - 1)]
                i0 = xs.index(-aw / 2)
                itf = top_b[i0]
                free = [c for c in top_b if c != itf]
                bb = geo.addLine(b0, b1)
                br = geo.addLine(b1, pb[-1])
                bl = geo.addLine(pb[0], b0)
                cb = geo.addCurveLoop([bb, br, *[-c for c in reversed(top_b)], bl])
                sb = geo.addPlaneSurface([cb])
                ar = geo.addLine(pb[i0 + 1], a1)
                at = geo.addLine(a1, a0)
                al = geo.addLine(a0, pb[i0])
                ca = geo.addCurveLoop([itf, ar, at, al])
                sa = geo.addPlaneSurface([ca])
                geo.synchronize()
                if structured and not free:
                    nx = max(1, round(aw / h)) + 1
                    for c in (itf, at, bb):
                        gmsh.model.mesh.setTransfiniteCurve(c, nx)
                    for c, L in ((ar, ah), (al, ah), (br, bh), (bl, bh)):
                        gmsh.model.mesh.setTransfiniteCurve(c, max(1, round(L / h)) + 1)
                    gmsh.model.mesh.setTransfiniteSurface(sa)
                    gmsh.model.mesh.setTransfiniteSurface(sb)
                groups = {(2, "a"): [sa], (2, "b"): [sb], (1, "interface"): [itf],
                          (1, "a_top"): [at], (1, "a_left"): [al], (1, "a_right"): [ar],
                          (1, "b_bottom"): [bb], (1, "b_left"): [bl], (1, "b_right"): [br]}
                if free:
                    groups[(1, "b_top_free")] = free
                corner = pb[i0]
            elif layout == "side":
                (aw, ah), (bw, _) = a, b
                p = [geo.addPoint(x, y, 0, h) for x, y in
                     ((-aw, 0), (0, 0), (bw, 0), (bw, ah), (0, ah), (-aw, ah))]
                l01, l12, l23 = geo.addLine(p[0], p[1]), geo.addLine(p[1], p[2]), \
                    geo.addLine(p[2], p[3])
                l34, l45, l50 = geo.addLine(p[3], p[4]), geo.addLine(p[4], p[5]), \
                    geo.addLine(p[5], p[0])
                itf = geo.addLine(p[1], p[4])
                sa = geo.addPlaneSurface([geo.addCurveLoop([l01, itf, l45, l50])])
                sb = geo.addPlaneSurface([geo.addCurveLoop([l12, l23, l34, -itf])])
                geo.synchronize()
                if structured:
                    for c, L in ((l01, aw), (l45, aw), (l12, bw), (l34, bw),
                                 (itf, ah), (l50, ah), (l23, ah)):
                        gmsh.model.mesh.setTransfiniteCurve(c, max(1, round(L / h)) + 1)
                    gmsh.model.mesh.setTransfiniteSurface(sa)
                    gmsh.model.mesh.setTransfiniteSurface(sb)
                groups = {(2, "a"): [sa], (2, "b"): [sb], (1, "interface"): [itf],
                          (1, "a_left"): [l50], (1, "a_top"): [l45], (1, "a_bottom"): [l01],
                          (1, "b_right"): [l23], (1, "b_top"): [l34], (1, "b_bottom"): [l12]}
                corner = p[0]
            else:
                raise ValueError(f"unknown layout {layout!r}")
            for (dim, name), tags in groups.items():
                gmsh.model.addPhysicalGroup(dim, tags, name=name)
            gmsh.model.addPhysicalGroup(0, [corner], name="a_corner")
            gmsh.model.mesh.generate(2)
            gmsh.write(str(path))

    on_rank_zero(comm, build)
    return pathlib.Path(comm.bcast(str(path), root=0))


def stacked_blocks(path: str | pathlib.Path, comm: MPI.Comm, width: float,
                   heights: tuple[float, ...], h: float) -> pathlib.Path:
    """Write a mesh of rectangles of one width stacked bottom up, with structured triangles.

    Physical names: ``block<k>`` (cells, ``block0`` at the bottom), ``joint<k>`` (the
    interface between blocks k and k + 1), ``base`` (the bottom of ``block0``),
    ``left<k>`` (the left side of block k).
    """
    path = pathlib.Path(path)

    def build() -> None:
        with gmsh_session():
            geo = gmsh.model.geo
            ys = [0.0]
            for height in heights:
                ys.append(ys[-1] + height)
            left = [geo.addPoint(-width / 2, y, 0, h) for y in ys]
            right = [geo.addPoint(width / 2, y, 0, h) for y in ys]
            levels = [geo.addLine(p, q) for p, q in zip(left, right, strict=True)]
            sides = [(geo.addLine(left[k + 1], left[k]), geo.addLine(right[k], right[k + 1]))
                     for k in range(len(heights))]
            surfaces = [geo.addPlaneSurface([geo.addCurveLoop(
                [levels[k], sides[k][1], -levels[k + 1], sides[k][0]])])
                for k in range(len(heights))]
            geo.synchronize()
            nx = max(1, round(width / h)) + 1
            for c in levels:
                gmsh.model.mesh.setTransfiniteCurve(c, nx)
            for (sl, sr), height in zip(sides, heights, strict=True):
                for c in (sl, sr):
                    gmsh.model.mesh.setTransfiniteCurve(c, max(1, round(height / h)) + 1)
            for s in surfaces:
                gmsh.model.mesh.setTransfiniteSurface(s)
            for k, s in enumerate(surfaces):
                gmsh.model.addPhysicalGroup(2, [s], name=f"block{k}")
                gmsh.model.addPhysicalGroup(1, [sides[k][0]], name=f"left{k}")
            for k in range(1, len(heights)):
                gmsh.model.addPhysicalGroup(1, [levels[k]], name=f"joint{k - 1}")
            gmsh.model.addPhysicalGroup(1, [levels[0]], name="base")
            gmsh.model.mesh.generate(2)
            gmsh.write(str(path))

    on_rank_zero(comm, build)
    return pathlib.Path(comm.bcast(str(path), root=0))


#: The three stacked blocks of :func:`three_blocks` (m, bottom up) and their densities.
THREE_WIDTH, THREE_HEIGHTS = 0.4, (0.2, 0.15, 0.1)
THREE_DENSITIES = (1800.0, 2300.0, 2500.0)


def three_blocks(path: str | pathlib.Path, comm: MPI.Comm, young_modulus: float,
                 penalty: float, gap: float = 0.0, tilt: float = 0.0) -> ContactModel:
    """Three stacked blocks on a :func:`stacked_blocks` mesh of ``THREE_*`` sizes.

    Gravity, Rayleigh damping (α = 5 1/s, β = 1e-6 s), the base fixed, μ = 0.3 on
    ``joint0`` and 0.6 on ``joint1``, and a triangular pulse on the top block's left side
    (``left2``) over 4 ms whose peak force is 1.5 × 0.6 × the top block's weight: it
    slides on ``joint1``. ``gap``: joint1's initial gap g₀ (m); ``tilt``: the mesh turned
    by this angle (rad) about the origin, so that the interfaces' normals and tangents have
    two nonzero components (gravity and the pulse stay as given).
    """
    g = 9.81
    w2 = THREE_DENSITIES[2] * g * THREE_WIDTH * THREE_HEIGHTS[2]

    def pulse(t: float) -> float:
        s = t / 4e-3
        return 1.5 * 0.6 * w2 / THREE_HEIGHTS[2] * max(0.0, 1.0 - abs(2.0 * s - 1.0)) \
            if 0 <= s <= 1 else 0.0

    bodies = [Body(f"block{k}", Material(ρ, 0.2, young_modulus=young_modulus))
              for k, ρ in enumerate(THREE_DENSITIES)]
    data = read_mesh(path, comm)
    if tilt:
        x = data.mesh.geometry.x
        c, s = math.cos(tilt), math.sin(tilt)
        x[:, 0], x[:, 1] = c * x[:, 0] - s * x[:, 1], s * x[:, 0] + c * x[:, 1]
    return ContactModel(data, bodies,
                        [ContactPair("joint0", "block1", "block0", penalty, friction=0.3),
                         ContactPair("joint1", "block2", "block1", penalty, friction=0.6,
                                     gap=gap)],
                        [Fixed("base")], [SurfaceLoad("left2", (1.0, 0.0), pulse)],
                        gravity=(0.0, -g), damping=Damping(alpha=5.0, beta=1e-6))


def two_block_case(mesh: str | pathlib.Path, head: str = "", tail: str = "") -> str:
    """The TOML of a case on a :func:`two_rectangles` mesh (the tests' two-block case).

    Bodies ``a`` and ``b`` (2000 kg/m³, ν = 0.25, E = 1 GPa), frictionless contact of
    ``a`` (slave) on ``b`` over ``interface`` (penalty 1e12 N/m³), ``b_bottom`` fixed,
    dt = 1e-4 s to 1e-3 s.

    Args:
        mesh: The ``.msh`` file (``mesh.source``).
        head: Top-level keys (before the tables), e.g. ``name = "x"``.
        tail: Further tables, e.g. ``[loads.…]``.
    """
    return f'''{head}
mesh.source = "{mesh}"
[bodies.a]
density = 2000.0
poisson = 0.25
young_modulus = 1e9
[bodies.b]
density = 2000.0
poisson = 0.25
young_modulus = 1e9
[contact.interface]
slave = "a"
master = "b"
penalty = 1e12
[fixed.b_bottom]
[time]
dt = 1e-4
end_time = 1e-3
{tail}
'''


class Killed(Exception):
    """Stands for a kill (not a BreakwaterError: the run does not clean up)."""


def run_killed_at(run: Callable[[pathlib.Path], Any], directory: pathlib.Path, t: float,
                  monkeypatch: pytest.MonkeyPatch) -> None:
    """``run(directory)``, killed (:class:`Killed`) at the first step from time ``t``."""
    solve = GN22.solve

    def killed(self: GN22) -> int:
        if float(self.t.value) >= t:
            raise Killed("killed")
        return solve(self)

    with monkeypatch.context() as mp:
        mp.setattr(GN22, "solve", killed)
        with pytest.raises(Killed):
            run(directory)
