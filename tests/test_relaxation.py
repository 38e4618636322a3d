"""The static initial state of general contact pairs (breakwater.statics.relaxation, issue 12).

A block ``block`` (W × H) rests on a wider base ``base`` fixed at its bottom, meshed
separately (:mod:`meshes.apart`) with element sizes W/7 and 0.4/8 (ratio 1.75), a general
pair (block_bottom on base_top), the paper's χ = 1e-10 m/s, gravity tilted by θ:

- θ = 0: the frictionless state. Vertical equilibrium of the block, exact for the FE
  solution too (the virtual displacements (0, 1) and (0, y) are in the P2 space, and the
  block's contact forces act at y = 0): contact resultant = weight, and the mean σ_yy
  over the block = −ρ g H/2 (each horizontal section carries the weight above it,
  ∫σ_yy dx = −ρ g W (H − y), averaged over y). The dynamics then starts at rest,
  where the undeformed start (the state before the relaxation) drops the block onto
  its penalty spring and oscillates.
- θ = 10° < atan μ (μ = 0.3, friction angle 16.7°): no frictionless state, a
  frictional one; the dynamics starts at rest and creeps at the regularised law's
  v = χF/sqrt((μN)² − F²) only (as tests/test_initial.py for conforming pairs).
- θ = 25°: no frictional state: the block is held up to t = 0 (one warning naming it)
  and slides from rest, ½ g (sinθ − μ cosθ) t² for a rigid block on a rough incline
  (Meriam & Kraige, *Engineering Mechanics: Dynamics*, §3/4).

Under ``mpiexec -n 2`` rank 0 repeats the static state serially (on ``COMM_SELF``): it
must agree to 1e-10 of its scale, or to the positions' round-off. E = 1e11 and
ε_n = 1e13 N/m³ make the block nearly rigid (as tests/test_initial.py).
"""

from __future__ import annotations

import itertools
import logging
import pathlib
import time

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
import ufl
from breakwater.meshes.apart import Rectangle, rectangles
from dolfinx import fem

from breakwater.config.runspec import InitialSpec
from breakwater.contact.general import SurfaceContact
from breakwater.contact.surfaces import SurfacePair
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, Damping, Fixed, Material
from breakwater.statics.initial import InitialState, initial_state
from breakwater.stepping.gn22 import GN22

COMM = MPI.COMM_WORLD

W, H = 0.2, 0.05             # the block (m)
ρ, ν, E = 2000.0, 0.25, 1e11
PENALTY = 1e13               # N/m³
μ, χ, g = 0.3, 1e-10, 9.81
BELOW, ABOVE = 10.0, 25.0    # degrees


def _mesh(folder: pathlib.Path, comm: MPI.Comm) -> pathlib.Path:
    name = "blocks.msh" if comm.size == COMM.size else "blocks_serial.msh"
    return rectangles(folder / name, comm, [Rectangle("base", -0.2, -0.05, 0.4, 0.05, 8, 2),
                                            Rectangle("block", -0.1, 0.0, W, H, 7, 2)])


@pytest.fixture(scope="module")
def mesh_path(folder: pathlib.Path) -> pathlib.Path:
    return _mesh(folder, COMM)


def _model(path: pathlib.Path, θ: float, comm: MPI.Comm = COMM,
           loading: str = "frictional") -> ContactModel:
    mat = Material(ρ, ν, young_modulus=E)
    t = np.radians(θ)
    pair = SurfacePair("c", "block", "base", "block_bottom", "base_top", PENALTY,
                       friction=μ, regularisation=χ)
    model = ContactModel(read_mesh(path, comm), [Body("base", mat), Body("block", mat)],
                         fixed=[Fixed("base_bottom")], gravity=(g * np.sin(t), -g * np.cos(t)),
                         surface_pairs=[pair])
    model.initial = InitialSpec(loading=loading)
    return model


def _static(model: ContactModel) -> tuple[InitialState, float]:
    model.set_time(0.0)
    t0 = time.perf_counter()
    state = initial_state(model)
    return state, time.perf_counter() - t0


def _block_mean(u: fem.Function, comm: MPI.Comm) -> np.ndarray:
    """The mean nodal displacement of a body (every rank)."""
    owned = u.x.array.reshape(-1, 2)[:u.function_space.dofmap.index_map.size_local]
    return comm.allreduce(owned.sum(axis=0)) / comm.allreduce(len(owned))


def _run(model: ContactModel, state: InitialState | None, dt: float, steps: int
         ) -> dict[str, np.ndarray]:
    """GN22 from the state (None: the undeformed state at rest): the block's mean
    displacement at every step, from t = 0."""
    s = GN22(model, dt)
    s.initialise(*((state.u, state.v) if state is not None else ()))
    comm = model.comm
    provider = s.surfaces[-1]
    assert isinstance(provider, SurfaceContact)
    a0 = max(comm.allreduce(float(np.abs(a.x.array).max(initial=0.0)), op=MPI.MAX)
             for a in s.a)
    x = [_block_mean(s.u[1], comm)]
    force = provider.resultant()
    for _ in range(steps):
        s.step()
        x.append(_block_mean(s.u[1], comm))
    out = {"x": np.array(x), "a0": np.array(a0), "force": force,
           "t": dt * np.arange(steps + 1)}
    s.destroy()
    return out


def _print(text: str) -> None:
    if COMM.rank == 0:
        print("\n" + text)


@pytest.mark.parametrize("loading", ["frictional", "frictionless"])
def test_resting_block_weight_stress_and_rest(mesh_path: pathlib.Path, loading: str) -> None:
    """θ = 0: the static state (the weight applied with friction, ``[initial] loading =
    "frictional"``, or the frictionless state) carries the weight, the mean σ_yy is
    −ρgH/2, and the dynamics starts at rest."""
    model = _model(mesh_path, 0.0, loading=loading)
    state, seconds = _static(model)
    weight = model.weight()[1]
    assert state.kind == loading and state.held == []
    assert state.relaxation is not None
    _print(f"resting block ({loading}): {state.relaxation['pseudo_steps']} pseudo steps, "
           f"{state.iterations} Newton iterations, {seconds:.2f} s")
    # Mean σ_yy of the block: the relaxation's residual (1e-9 of the load norm) and the
    # round-off of the stress of a stiff body (E ε ~ ρgH from ε ~ 1e-11) allow 1e-6.
    b = model.bodies[1]
    e = ufl.sym(ufl.grad(state.u[1]))
    σ_yy = (2 * b.μ * e + b.λ * ufl.tr(e) * ufl.Identity(2))[1, 1]
    mean = model.assemble(model.form(σ_yy * b.dx)) / (W * H)
    _print(f"mean σ_yy {mean:.8g} Pa, −ρgH/2 = {-ρ * g * H / 2:.8g} Pa")
    assert mean == pytest.approx(-ρ * g * H / 2, rel=1e-6)
    # Rest: 200 steps of 1e-4 s with no load. From the static state the block's mean
    # displacement changes by round-off only; from the undeformed state it falls onto
    # its penalty spring and oscillates by the whole settlement.
    rest = _run(model, state, 1e-4, 200)
    undeformed = _run(model, None, 1e-4, 200)
    # Resultant = weight: the same tolerance as σ_yy.
    assert rest["force"][1] == pytest.approx(weight, rel=1e-6)
    assert abs(rest["force"][0]) < 1e-6 * weight
    settlement = abs(rest["x"][0][1])
    change = np.abs(rest["x"] - rest["x"][0]).max()
    swing = np.abs(undeformed["x"] - rest["x"][0]).max()
    _print(f"settlement {settlement:.3e} m, |a0| {float(rest['a0']):.2e} m/s²; change over "
           f"200 steps {change:.2e} m from the static state, {swing:.2e} m from the "
           f"undeformed one")
    assert swing > 0.5 * settlement
    # Frictional: the interface carries the shear of the block's Poisson expansion held
    # by friction, which the regularised law carries by creeping at a fraction of χ
    # (measured 2.8e-14 m over 0.02 s, against χ t = 2e-12 m).
    assert change < (1e-6 * settlement if loading == "frictionless" else χ * 0.02)


def test_incline_below_the_friction_angle_stays_at_rest(mesh_path: pathlib.Path) -> None:
    """θ = 10°: a frictional state; the block starts at rest and creeps < 1e-8 m in 0.1 s
    (the regularised law's steady creep, 7e-12 m)."""
    model = _model(mesh_path, BELOW)
    state, seconds = _static(model)
    assert state.kind == "frictional" and state.held == []
    assert state.relaxation is not None
    _print(f"10° incline: {state.relaxation['pseudo_steps']} pseudo steps, "
           f"{state.iterations} Newton iterations, {seconds:.2f} s")
    dt = 1e-3
    r = _run(model, state, dt, 100)
    creep = np.abs(r["x"] - r["x"][0]).max()
    F_over_μN = np.tan(np.radians(BELOW)) / μ
    v_creep = χ * F_over_μN / np.sqrt(1.0 - F_over_μN**2)
    _print(f"|a0| {float(r['a0']):.2e} m/s², creep {creep:.3e} m over 0.1 s (regularised "
           f"law: {v_creep * 0.1:.2e} m)")
    assert creep < 1e-8
    # What creeps is the law's steady creep (measured +2.5 %: the elastic block's
    # pressure is not uniform); 10 % allows for it, as tests/test_initial.py.
    assert np.abs(r["x"][-1] - r["x"][0]).max() == pytest.approx(v_creep * 0.1, rel=0.1)


def test_incline_asked_frictionless_warns_it_is_frictional(
        mesh_path: pathlib.Path, caplog: pytest.LogCaptureFixture) -> None:
    """θ = 10° with ``[initial] loading = "frictionless"``: no frictionless state exists
    (the block would slide), and the frictional one is used with one warning saying so
    (before, a debug line: only the summary's ``static.initial_state`` told)."""
    model = _model(mesh_path, BELOW, loading="frictionless")
    with caplog.at_level(logging.WARNING, logger="breakwater.statics.relaxation"):
        state, _ = _static(model)
    assert state.kind == "frictional" and state.held == []
    warnings = [rec.getMessage() for rec in caplog.records if rec.levelno == logging.WARNING]
    if COMM.rank == 0:
        assert len(warnings) == 1 and "no frictionless static equilibrium" in warnings[0]
    else:
        assert warnings == []


def test_incline_above_the_friction_angle_is_held_and_released(
        mesh_path: pathlib.Path, caplog: pytest.LogCaptureFixture) -> None:
    """θ = 25°: held up to t = 0 (one warning naming the block), then it slides from
    rest as the rigid block, ½ g (sinθ − μ cosθ) t² along x."""
    model = _model(mesh_path, ABOVE)
    with caplog.at_level(logging.WARNING, logger="breakwater.statics.relaxation"):
        state, seconds = _static(model)
    assert state.kind == "held" and state.held == ["block"]
    assert state.relaxation is not None
    warnings = [rec.getMessage() for rec in caplog.records if rec.levelno == logging.WARNING]
    if COMM.rank == 0:
        assert len(warnings) == 1 and "body 'block' cannot be held" in warnings[0]
    else:
        assert warnings == []
    _print(f"25° incline: {state.relaxation['pseudo_steps']} pseudo steps, "
           f"{state.iterations} Newton iterations, {seconds:.2f} s")
    dt = 5e-4
    r = _run(model, state, dt, 200)
    t = np.radians(ABOVE)
    reference = 0.5 * g * (np.sin(t) - μ * np.cos(t)) * r["t"][-1] ** 2
    slide = r["x"][-1][0] - r["x"][0][0]
    _print(f"slide {slide:.6e} m, rigid block {reference:.6e} m ({slide / reference - 1:+.3%})")
    # 2 %: the rigid limit and GN22's first-order start, as tests/test_initial.py.
    assert slide == pytest.approx(reference, rel=0.02)


@pytest.mark.skipif(COMM.size < 2, reason="compares serial and parallel runs")
def test_static_state_equal_serial(mesh_path: pathlib.Path, folder: pathlib.Path) -> None:
    """The static states (θ = 0 and 10°) on 2 ranks equal the serial ones (every rank
    evaluates the same contact points in the same order), to 1e-10 of their scale or,
    where that is smaller, to the round-off of the positions (eps × 0.4 m = 9e-17 m: the
    displacements of these stiff bodies, ~1e-9 m, are differences of positions of
    0.1 m, the gap's round-off is 1e-17 m). Measured 5.8e-19 m at θ = 0 and 4.0e-19 m
    at 10° (6e-10 and 4e-10 of the scale)."""
    for θ in (0.0, BELOW):
        model = _model(mesh_path, θ)
        parallel = _nodal(model, _static(model)[0])
        error = None
        if COMM.rank == 0:
            path = _mesh(folder, MPI.COMM_SELF)
            model = _model(path, θ, MPI.COMM_SELF)
            serial = _nodal(model, _static(model)[0])
            assert all(np.abs(p[:, :2] - s[:, :2]).max() < 1e-12
                       for p, s in zip(parallel, serial, strict=True))
            scale = max(np.abs(s[:, 2:]).max() for s in serial)
            error = max(np.abs(p[:, 2:] - s[:, 2:]).max()
                        for p, s in zip(parallel, serial, strict=True))
            print(f"\nθ = {θ}°: 2 ranks against serial {error:.2e} m, {error / scale:.2e} "
                  f"of the scale {scale:.3e} m")
            error = error / max(1e-10 * scale, np.finfo(float).eps * 0.4)
        assert COMM.bcast(error, root=0) < 1.0


def _nodal(model: ContactModel, state: InitialState) -> list[np.ndarray]:
    """Per body: (x, y, u_x, u_y) of every node, gathered and sorted by coordinates."""
    out = []
    for b, u in zip(model.bodies, state.u, strict=True):
        n = b.V.dofmap.index_map.size_local
        x = b.V.tabulate_dof_coordinates()[:n, :2]
        rows = np.concatenate(model.comm.allgather(
            np.hstack([x, u.x.array.reshape(-1, 2)[:n]])))
        key = np.round(rows[:, :2], 10)  # the same order whatever the coordinates' round-off
        out.append(rows[np.lexsort((key[:, 1], key[:, 0]))])
    return out


def test_frictional_state_on_a_soft_base_starts_in_equilibrium(mesh_path: pathlib.Path) -> None:
    """The Goda case's materials on the blocks (a stiff block, E = 4.8e9, on a soft base,
    5.7e6; ε_n = 5e8, μ = 0.65, Rayleigh damping 0.023/0.023), frictional loading: at
    t = 0 the pair carries no net horizontal force and the bodies do not accelerate.

    The block's corners and middle sit on base vertices, where the master's tangent has
    a kink. The static stage's slip u/τ includes the penalty's overlap, and its friction
    there depends on which facet's tangent it takes: re-projected at the state for
    t = 0, the other one gave a net friction of 7.3 N/m (3 % of the weight) and
    265 m/s² at t = 0 (measured). The slip velocities now carry the last step's
    friction (``contact.general.start_slip``): 3e-8 N/m and 0.08 m/s² (measured).
    Bounds: 1e-6 of the weight (the existing test's), 1 m/s²."""
    pair = SurfacePair("c", "block", "base", "block_bottom", "base_top", 5e8, friction=0.65,
                       regularisation=χ)
    model = ContactModel(read_mesh(mesh_path, COMM),
                         [Body("base", Material(1650.0, 0.25, young_modulus=5.7e6)),
                          Body("block", Material(2314.0, 0.2, young_modulus=4.8e9))],
                         fixed=[Fixed("base_bottom")], gravity=(0.0, -g),
                         surface_pairs=[pair], damping=Damping(alpha=0.023, beta=0.023))
    model.initial = InitialSpec(loading="frictional")
    state, _ = _static(model)
    assert state.kind == "frictional"
    rest = _run(model, state, 1e-4, 3)
    weight = model.weight()[1]
    _print(f"soft base: net force at t = 0 {rest['force']} N/m, |a0| {float(rest['a0']):.2e}")
    assert abs(rest["force"][0]) < 1e-6 * weight
    assert float(rest["a0"]) < 1.0


def test_block_held_along_x_by_its_side_stays_at_rest(mesh_path: pathlib.Path) -> None:
    """The block's left side fixed along x (a roller), E = 1e9 Pa, μ = 0.65, frictional
    loading: the friction carries the bodies' Poisson expansions against the roller, and
    the dynamics keeps that state (issue 25).

    The block's lower left corner is a slave node held along x, the interface's
    tangent: its static friction is the base's slip under it. Its start slip is now the
    base's nodes' velocity (``newtonaids.slip_velocities_at``); before, it had none at
    t = 0, the friction there and its reaction on the base were lost: |a₀| 17.8 m/s²,
    the friction resultant −4.13 N/m at t = 0 (the state's: −2.075), then 4.74, −10.54,
    −0.32 N/m, velocities up to 1.9e-4 m/s (measured). Bounds: the start slip is at most
    RELEASE χ = 1e-8 m/s (a master node's up to twice that: the least-squares velocity
    of a facet whose quadratic shape values are partly negative), a creep of at most
    RELEASE χ t = 3e-11 m over the 3 steps, which changes the elastic forces by
    ~E × 3e-11 m = 0.03 N/m: the friction resultant stays that of t = 0 to that
    (measured 5.7e-5 N/m), |a₀| below 1e-3 g (measured 1.2e-7 m/s²)."""
    mat = Material(ρ, 0.2, young_modulus=1e9)
    pair = SurfacePair("c", "block", "base", "block_bottom", "base_top", PENALTY,
                       friction=0.65, regularisation=χ)
    model = ContactModel(read_mesh(mesh_path, COMM), [Body("base", mat), Body("block", mat)],
                         fixed=[Fixed("base_bottom"), Fixed("block_left", (0,))],
                         gravity=(0.0, -g), surface_pairs=[pair])
    model.initial = InitialSpec(loading="frictional")
    state, _ = _static(model)
    assert state.kind == "frictional"
    s = GN22(model, 1e-3)
    s.initialise(state.u, state.v)
    provider = s.surfaces[-1]
    assert isinstance(provider, SurfaceContact)
    a0 = max(COMM.allreduce(float(np.abs(a.x.array).max(initial=0.0)), op=MPI.MAX)
             for a in s.a)
    friction = [provider.resultants()[1][0]]
    fastest = 0.0
    for _ in range(3):
        s.step()
        friction.append(provider.resultants()[1][0])
        fastest = max(fastest, *(COMM.allreduce(float(np.abs(v.x.array).max(initial=0.0)),
                                                op=MPI.MAX) for v in s.v))
    s.destroy()
    _print(f"block on a side roller: |a0| {a0:.2e} m/s², friction {friction} N/m, "
           f"max |v| {fastest:.2e} m/s")
    assert abs(friction[0]) > 1.0  # the state carries friction (2.075 N/m)
    assert np.ptp(friction) < 1e9 * 100 * χ * 3e-3, friction
    assert a0 < 1e-3 * g
    assert fastest < 2 * 100 * χ


def test_a_frictionless_state_that_moves_a_body_sideways(mesh_path: pathlib.Path) -> None:
    """``rigidmodes.sideways`` and ``drift``: the block (no fixed group) moved sideways
    more than DRIFT times its sinking in a frictionless state is refused in one line
    where its pair has friction (the frictional loading would hold it), warned where
    μ = 0; the base (fixed) is never measured; a smaller move passes. (The Goda caisson
    meshed in quadrilaterals moved 0.90 mm, 5.9 times its sinking, in its frictionless
    state: the gauges' peaks read 1.54 mm for 2.44; in triangles 1.4e-9 m.) Each body's
    nodes are all moved by (side, −sink): its mean move is exactly that."""
    from breakwater.statics.rigidmodes import DRIFT, drift, sideways

    sink = 1.5e-4
    rough = _model(mesh_path, 0.0, loading="frictionless")
    smooth = ContactModel(read_mesh(mesh_path, COMM),
                          [Body("base", Material(ρ, ν, young_modulus=E)),
                           Body("block", Material(ρ, ν, young_modulus=E))],
                          fixed=[Fixed("base_bottom")], gravity=(0.0, -g),
                          surface_pairs=[SurfacePair("c", "block", "base", "block_bottom",
                                                     "base_top", PENALTY)])
    smooth.initial = InitialSpec(loading="frictionless")
    for model, side in itertools.product((rough, smooth), (0.9e-3, 0.5 * DRIFT * sink)):
        u = [fem.Function(b.V) for b in model.bodies]
        for f in u:
            f.x.array.reshape(-1, 2)[:] = (side, -sink)  # both bodies: only the block is free
        moved = sideways(model, u)
        assert list(moved) == ["block"]
        assert moved["block"] == pytest.approx((side, sink), rel=1e-12)
        refusal, warnings = drift(model, moved)
        if side < DRIFT * sink:
            assert (refusal, warnings) == (None, [])
        elif model is rough:
            assert warnings == [] and refusal is not None and "\n" not in refusal
            assert refusal.startswith("bodies.block: the frictionless static state moved it "
                                      "0.9 mm sideways, 6 times as far as it sank (0.15 mm)")
            assert refusal.endswith('[initial] loading = "frictional" (the default with '
                                    "friction: 'c' μ = 0.3) gives the state friction holds")
        else:
            assert refusal is None and len(warnings) == 1
            assert warnings[0].startswith("bodies.block: the frictionless static state moved "
                                          "it 0.9 mm sideways")
            assert "without friction ('c' μ = 0)" in warnings[0]
    # The frictional loading: not judged (with friction its state is never frictionless).
    rough.initial = InitialSpec(loading="frictional")
    refusal, warnings = drift(rough, {"block": (0.9e-3, sink)})
    assert refusal is None and warnings == []
