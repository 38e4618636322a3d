"""Plane-strain Hertz contact through a general (non-matching) pair (issue 12).

An elastic half-cylinder of radius R = 1 m, its flat top loaded by a uniform pressure
(force P per unit length), pressed onto an elastic block of the same material
(E = 1 GPa, ν = 0.25: E* = E/(2(1 − ν²)), from 1/E* = (1 − ν₁²)/E₁ + (1 − ν₂²)/E₂),
frictionless; by symmetry the quarter x ≥ 0 is modelled (u_x = 0 on both bodies' axis
x = 0), the block (3 m × 3 m) fixed at its bottom. The bodies are meshed separately
(:mod:`meshes.hertz`, element size ``fine`` within 2b of the first contact point, the
meshes do not match); the cylinder's lower arc is the slave. References (Johnson,
Contact Mechanics, 1985, §4.3, eq. 4.45): the contact half-width b = sqrt(4PR/(πE*))
and the peak pressure p_max = 2P/(πb). P is chosen for b = R/10 (strains ≈ 1 %).

The state is reached quasi-statically: the load ramps up over 20 ms (10 steps of 2 ms)
and is then held, with mass-proportional damping α = 1000 1/s (about critical for the
lowest modes, ω ≈ 420-800 1/s) and GN22 β₁ = β₂ = 1, to t = 80 ms; a step whose
Newton fails (the contact front crossing points) is retried as two half steps. The
cylinder starts moved down by b²/(20R) (its vertical position is free, so the loaded
equilibrium does not depend on it; a point contact would give Newton no stiffness).

Measured: p_max is the largest pressure at the slave's integration points (3 Gauss
points per segment); b is the root of the gap between the outermost penetrating point
and the next one (linear interpolation). Penalty ε_n = 1e12 N/m³: the penetration
p_max/ε_n ≈ 3e-5 m is 0.5 % of the gap b²/(2R) = 5e-3 m across the contact zone; it
softens the contact like an elastic layer (E*/(ε_n b) = 0.5 %), lengthening b and
lowering p_max by a fraction of that.
"""

from __future__ import annotations

import pathlib
from typing import Any

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from breakwater.meshes.hertz import hertz

from breakwater.common.errors import ConvergenceError
from breakwater.contact.general import SurfaceContact
from breakwater.contact.slavepoints import SlavePoints
from breakwater.contact.surfaces import SurfacePair
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, Damping, Fixed, Material, SurfaceLoad
from breakwater.stepping.gn22 import GN22, GN22Parameters

COMM = MPI.COMM_WORLD
R, E, NU = 1.0, 1e9, 0.25
E_STAR = E / (2 * (1 - NU**2))
B = 0.1 * R  # the reference half-width
P = np.pi * E_STAR * B**2 / (4 * R)  # b = sqrt(4PR/(πE*))  ⇒  P = πE*b²/(4R)
P_MAX = 2 * P / (np.pi * B)
RAMP, DT, END = 0.02, 2e-3, 0.08


def _advance(stepper: GN22, dt: float, depth: int = 0) -> None:
    """One step of dt, or two half steps where Newton fails (up to 4 halvings)."""
    try:
        stepper.stage(dt)
        stepper.solve()
    except ConvergenceError:
        if depth >= 4:
            raise
        for _ in range(2):
            _advance(stepper, dt / 2, depth + 1)
        return
    stepper.update()


def hertz_run(path: pathlib.Path, fine: float, comm: MPI.Comm = COMM) -> dict[str, Any]:
    """Press the cylinder (element size ``fine`` × b near the contact).

    Returns:
        b, p_max (integration points), the resultant, h, the slave nodes' x and
        pressure field, and the field's and the integration points' ∫p.
    """
    mesh = hertz(path, comm, R, 3 * R, 3 * R, fine * B, 0.3 * R, 2 * B,
                 overlap=0.1 * B**2 / (2 * R))
    material = Material(density=2000.0, poisson=NU, young_modulus=E)
    pair = SurfacePair("hertz", "cylinder", "block", "cylinder_contact", "block_top", 1e12)
    model = ContactModel(
        read_mesh(mesh, comm), [Body("cylinder", material), Body("block", material)],
        surface_pairs=[pair], damping=Damping(alpha=1000.0),
        fixed=[Fixed("block_bottom"), Fixed("block_axis", (0,)), Fixed("cylinder_axis", (0,))],
        loads=[SurfaceLoad("cylinder_top", (0.0, -P / (2 * R)),
                           lambda t: min(t / RAMP, 1.0))])
    stepper = GN22(model, DT, GN22Parameters(1.0, 1.0))
    stepper.initialise()
    provider = stepper.surfaces[-1]
    assert isinstance(provider, SurfaceContact)
    for _ in range(round(END / DT)):
        _advance(stepper, DT)
    state = provider.state()
    force = provider.resultant()
    nodal = SlavePoints.nodes(provider)
    field = nodal.evaluate(provider.interface_values(stepper.u))
    stepper.destroy()
    order = np.argsort(state["x"][:, 0])
    x, p, gap = state["x"][order, 0], state["pressure"][order], state["gap"][order]
    last = np.flatnonzero(p > 0).max()
    b = x[last] + (x[last + 1] - x[last]) * -gap[last] / (gap[last + 1] - gap[last])
    assert nodal.weights is not None
    return {"b": float(b), "p_max": float(p.max()), "force": float(force[1]),
            "h": fine * B, "nodes_x": nodal.X[:, 0], "nodes_p": field["pressure"],
            "field_integral": float(nodal.weights @ field["pressure_dual"]),
            "integral": float(state["pressure"] @ state["weight"])}


def _table(rows: list[dict[str, Any]]) -> None:
    if COMM.rank == 0:
        print(f"\nHertz (b = {B:.4g} m, p_max = {P_MAX:.4g} Pa)")
        print("   h/b     b err    p_max err   ∫p/(P/2) − 1")
        for r in rows:
            print(f"{r['h'] / B:7.4f} {r['b'] / B - 1:+9.2e} {r['p_max'] / P_MAX - 1:+11.2e}"
                  f" {r['force'] / (P / 2) - 1:+11.2e}")


@pytest.fixture(scope="module")
def coarse(folder: pathlib.Path) -> dict[str, Any]:
    """The b/10 run, once for the module: :func:`test_hertz_coarse` and (serially)
    :func:`test_hertz_converges` assert different things on the same run (it holds
    only arrays and numbers; the stepper is destroyed inside :func:`hertz_run`)."""
    return hertz_run(folder / "hertz10.msh", 0.1)


def test_hertz_coarse(coarse: dict[str, Any]) -> None:
    """Element size b/10 near the contact (2 ranks, 7 s): b and p_max within 3 %
    (measured −1.62 % and −0.39 %), and the contact resultant balances the load
    within 1e-2 (measured −2.6e-3: the remaining dynamics at 80 ms); the nodal pressure
    field follows p(x) (:func:`_nodal_pressure`)."""
    r = coarse
    _table([r])
    assert abs(r["force"] / (P / 2) - 1) < 1e-2
    assert abs(r["b"] / B - 1) < 0.03
    assert abs(r["p_max"] / P_MAX - 1) < 0.03
    _nodal_pressure(r)


def _against_johnson(x: np.ndarray, p: np.ndarray, label: str) -> None:
    """Nodal pressures p at abscissae x against Johnson's p(x) = p₀ sqrt(1 − x²/b²)
    (§4.2): within 3 % of p₀ over |x| < 0.9 b (at least 15 nodes there), the node on
    the axis within 2 % of p₀."""
    exact = P_MAX * np.sqrt(np.clip(1 - (x / B) ** 2, 0.0, None))
    inside = np.abs(x) < 0.9 * B
    axis = int(np.argmin(np.abs(x)))
    error = np.abs(p - exact)[inside].max() / P_MAX
    if COMM.rank == 0:
        print(f"{label}: max |p − p(x)|/p₀ {error:.2e} over |x| < 0.9b "
              f"({inside.sum()} nodes), p(0)/p₀ − 1 {p[axis] / P_MAX - 1:+.2e}")
    assert inside.sum() >= 15
    assert error < 0.03
    assert abs(p[axis] / P_MAX - 1) < 0.02


def _nodal_pressure(r: dict[str, Any]) -> None:
    """The slave nodes' pressure field (static.npz, contact_<name>.bp) against Johnson's
    p(x) = p₀ sqrt(1 − x²/b²) (§4.2; x the nodes' reference abscissa, as the linear
    theory's, b and p₀ the reference's): within 3 % of p₀ over |x| < 0.9 b, the node
    on the axis within 2 % of p₀; the unclipped projection's integral Σ_k p_k ∫N_k
    (``pressure_dual``: ``pressure`` is it where positive) is the residual's ∫p to
    round-off. In the current abscissa the slave surface's tangential displacement
    (1.25 % of b inward at the edge) shortens the contact by as much: that is the
    −1.6 % of the b measured on the integration points' current positions."""
    _against_johnson(r["nodes_x"], r["nodes_p"], "nodal pressure")
    assert r["field_integral"] == pytest.approx(r["integral"], rel=1e-12)


@pytest.mark.serial
def test_hertz_converges(shared_dir: pathlib.Path, coarse: dict[str, Any]) -> None:
    """Element sizes b/10 (the module's :func:`coarse` run) and b/20 (serial: 50 s):
    the error in b decreases with h and both errors are within 3 % on the finer mesh.

    Measured (b, p_max errors): b/10 −1.62 %, −0.39 %; b/20 −1.37 %, −0.30 %; b/30
    −1.12 %, −0.49 % (77 s); b/40 p_max −0.40 % (6 min all three). The error in b
    falls with h; the one in p_max does not: it sits at the penalty's softening
    (E*/(ε_n b) = 0.5 %) and the remaining out-of-balance of the damped run (∫p
    within 0.2-0.3 % of P/2), so p_max is asserted within 1 % on every mesh. The
    nodal pressure field (:func:`_nodal_pressure`): b/10 0.39 %, b/20 0.40 % of p₀.
    """
    rows = [coarse, hertz_run(shared_dir / "hertz20.msh", 1 / 20)]
    _table(rows)
    for r in rows:
        _nodal_pressure(r)
    eb = [abs(r["b"] / B - 1) for r in rows]
    ep = [abs(r["p_max"] / P_MAX - 1) for r in rows]
    assert eb[1] < eb[0]
    assert eb[1] < 0.03 and ep[1] < 0.03
    assert max(ep) < 0.01


def test_hertz_mesh(shared_dir: pathlib.Path) -> None:
    """The generator's bodies and groups: the quarter disc's area πR²/4 (second-order
    geometry: the arc's mid-nodes on the circle; measured −8e-6 with sizes 0.3R to
    R/100), the block's 9R², the block's top 3R and the contact arc's length R·30°
    (measured −2e-7)."""
    import ufl
    from dolfinx import fem

    data = read_mesh(hertz(shared_dir / "hertzmesh.msh", COMM, R, 3 * R, 3 * R, B, 0.3 * R,
                           2 * B), COMM)
    groups = data.physical_groups

    def measure(name: str, dim: int) -> float:
        tags = data.cell_tags if dim == 2 else data.facet_tags
        m = ufl.Measure("dx" if dim == 2 else "ds", domain=data.mesh, subdomain_data=tags)
        form = fem.form(fem.Constant(data.mesh, 1.0) * m(groups[name][1]))
        return COMM.allreduce(fem.assemble_scalar(form), op=MPI.SUM)

    assert measure("cylinder", 2) == pytest.approx(np.pi * R**2 / 4, rel=1e-4)
    assert measure("block", 2) == pytest.approx(9 * R**2, rel=1e-12)
    assert measure("cylinder_contact", 1) == pytest.approx(R * np.pi / 6, rel=1e-4)
    assert measure("block_top", 1) == pytest.approx(3 * R, rel=1e-12)


def test_hertz_static_field(shared_dir: pathlib.Path) -> None:
    """The case through the command line (a ``.msh`` of second order, curved cells):
    the static state by relaxation (``breakwater.statics.relaxation``), two steps,
    the ParaView fields, figures and summary. The slave nodes' pressure field of
    ``static.npz`` (x: the nodes' reference abscissa) against Johnson's p(x) over
    |x| < 0.9 b on the b/10 mesh: within 3 % of p₀ (measured 0.29 %; the damped run
    of :func:`_nodal_pressure` 0.39 %), p₀ within 2 % (measured −0.27 %). Serial 12 s."""
    import tomli_w

    from breakwater import cli

    mesh = hertz(shared_dir / "hertz.msh", COMM, R, 3 * R, 3 * R, 0.1 * B, 0.3 * R, 2 * B,
                 overlap=0.1 * B**2 / (2 * R))
    case = shared_dir / "hertz.toml"
    material = {"density": 2000.0, "poisson": NU, "young_modulus": E}
    if COMM.rank == 0:
        case.write_text(tomli_w.dumps({
            "name": "hertz", "gravity": [0.0, 0.0], "mesh": {"source": str(mesh)},
            "bodies": {"cylinder": material, "block": material},
            "calibration": {"enabled": False},
            "fixed": {"block_bottom": {}, "block_axis": {"components": [0]},
                      "cylinder_axis": {"components": [0]}},
            "contact": {"hertz": {"slave": "cylinder", "master": "block",
                                  "slave_surface": "cylinder_contact",
                                  "master_surface": "block_top", "penalty": 1e12}},
            "loads": {"top": {"group": "cylinder_top", "pressure": P / (2 * R)}},
            "time": {"dt": 1e-4, "end_time": 2e-4},
            "output": {"field_interval": 1, "figures": True}}))
    COMM.barrier()
    out = shared_dir / "run"
    assert cli.main(["run", str(case), "--out", str(out), "--no-progress", "--quiet"]) == 0
    assert (out / "contact_hertz.bp").exists()
    assert (out / "figures" / "static_pressure.png").exists()
    with np.load(out / "static.npz") as data:
        x, p = data["contact_hertz_x"][:, 0], data["contact_hertz_pressure"]
    _against_johnson(x, p, "static field")
