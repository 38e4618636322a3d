"""Outputs of general contact pairs (:mod:`breakwater.contact.slavepoints`, issue 12 item 4).

- Matching meshes: a general pair's probe gives the conforming pairs' slip
  (u_s − u_m)·t exactly and their opening (u_s − u_m)·n to second order in the
  master's rotation (the general gap is measured along the current normal).
- A block pushed along a base by F = 1.5 μN (bodies meshed separately, run through
  :func:`breakwater.run.simulation.run`): the pair probe's slip is the rigid block's
  (F − μN) t²/(2m) (Coulomb friction, constant acceleration) and its sides are the
  point probes' displacements; its opening is −p/ε_n with p = N/w the mean pressure
  (the penalty law: the paper's eq. 11 penalised, as in its eq. 23); the ParaView pressure
  on the slave surface integrates to the normal resultant of the history; the snapshots
  hold the slave surface's arrays; the contact-quality report has the conforming pairs' keys.
- The example case with a pair probe through the command line, figures included.
- A run killed after its checkpoint resumes to the same probe history and report.
"""

from __future__ import annotations

import json
import pathlib

import numpy as np
import pytest
from blocks import run_killed_at
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from breakwater.meshes.apart import Rectangle, rectangles

from breakwater.common.errors import MeshError
from breakwater.common.files import read_history
from breakwater.config.runspec import OutputSpec, PairProbeSpec, ProbeSpec, TimeSpec
from breakwater.contact.general import SurfaceContact
from breakwater.contact.slavepoints import SlavePoints
from breakwater.contact.surfaces import SurfacePair
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, Damping, Fixed, Material, SurfaceLoad
from breakwater.outputs import quality
from breakwater.outputs.probes import PointProbe
from breakwater.stepping.gn22 import GN22

COMM = MPI.COMM_WORLD
G = 9.81
MATERIAL = Material(density=2000.0, poisson=0.25, young_modulus=1e9)


def _two_blocks(path: pathlib.Path) -> GN22:
    """A GN22 stepper of a 1 x 0.5 block on a base of its size, meshed apart (4 x 2 cells
    each, a general pair of ε_n = 1e10), the base fixed at its bottom."""
    pair = SurfacePair("c", "block", "base", "block_bottom", "base_top", 1e10)
    mesh = rectangles(path, COMM, [Rectangle("base", 0.0, -0.5, 1.0, 0.5, 4, 2),
                                   Rectangle("block", 0.0, 0.0, 1.0, 0.5, 4, 2)])
    model = ContactModel(read_mesh(mesh, COMM), [Body("base", MATERIAL),
                                                 Body("block", MATERIAL)],
                         fixed=[Fixed("base_bottom")], surface_pairs=[pair])
    return GN22(model, 1e-3)


def _provider(stepper: GN22) -> SurfaceContact:
    provider = stepper.surfaces[-1]
    assert isinstance(provider, SurfaceContact)
    return provider


def test_matching_meshes_give_the_conforming_definitions(shared_dir: pathlib.Path) -> None:
    """Matching meshes (4 elements on both sides of y = 0), the block translated by
    (d, −δ), the base by the linear field (−θy, θx): X̄₀ is the slave point itself, so
    the slip is the conforming (u_s − u_m)·t = d exactly (round-off); the gap is
    measured along the current normal of the master line y = θx, (−θ(X + d) − δ)/
    sqrt(1 + θ²), which differs from the conforming (u_s − u_m)·n = −δ − θX by θd
    (second order: a rotation times a slip)."""
    stepper = _two_blocks(shared_dir / "match.msh")
    contact, model = _provider(stepper), stepper.model
    base, block = stepper.u
    θ, d, δ = 1e-3, 2e-3, 1e-5
    base.interpolate(lambda x: np.stack([-θ * x[1], θ * x[0]]))
    block.interpolate(lambda x: np.stack([d + 0 * x[0], -δ + 0 * x[0]]))

    def gap(X: np.ndarray) -> np.ndarray:
        return (-θ * (X + d) - δ) / np.sqrt(1 + θ**2)

    for point in ((0.25, 0.0), (0.4, 0.0), (1.0, 0.0)):
        probe = contact.probe(point, "p")
        value = probe.values(COMM.allreduce(probe.local(stepper.u)))
        us = PointProbe(model, "block", point).value(stepper.u)
        um = PointProbe(model, "base", point).value(stepper.u)
        np.testing.assert_allclose([value["slave_ux"], value["slave_uy"]], us, atol=1e-15)
        np.testing.assert_allclose([value["master_ux"], value["master_uy"]], um, atol=1e-15)
        assert value["slip"] == pytest.approx(us[0] - um[0], rel=1e-12)
        assert value["opening"] == pytest.approx(gap(point[0]), rel=1e-12)
        assert abs(value["opening"] - (us[1] - um[1])) <= 1.01 * θ * d
    # The nodal fields: the same definitions at every slave node.
    nodes = SlavePoints.nodes(contact)
    state = nodes.evaluate(contact.interface_values(stepper.u))
    np.testing.assert_allclose(state["slip"], np.broadcast_to([d, 0.0], state["slip"].shape),
                               rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(state["gap"], gap(nodes.X[:, 0]), rtol=1e-12)
    # The node at X = 1 has slid past the end of the master (x = 1 + d): no projection,
    # no pressure; its gap is measured to X̄₀ = (1, 0), on the same line.
    past = nodes.X[:, 0] + d > 1.0
    assert past.sum() == 1
    np.testing.assert_allclose(state["law_pressure"], np.where(
        past, 0.0, contact.spec.penalty * -state["gap"]), rtol=1e-12)
    # The nodal pressure field: ∫ p_h = Σ_k p_k ∫N_k is the residual's ∫ p (round-off),
    # and where p is linear over a node's facets of equal length (every node but the
    # two ends and the one past the master's end, whose facet the pressure leaves)
    # it is the law at the node (the weighted mean of a linear function, weights N_k
    # symmetric about the node).
    lam = contact.normal_forces(contact.interface_values(stepper.u))
    assert nodes.weights is not None
    assert nodes.weights @ state["pressure"] == pytest.approx(lam.sum(), rel=1e-12)
    assert lam.sum() == pytest.approx(contact.state()["pressure"] @ contact.state()["weight"],
                                      rel=1e-12)
    inner = (nodes.X[:, 0] > 0) & (nodes.X[:, 0] < 0.7)
    np.testing.assert_allclose(state["pressure"][inner], state["law_pressure"][inner],
                               rtol=1e-9)
    # A point off the slave surface is an error.
    with pytest.raises(MeshError, match="not on the slave surface 'block_bottom'"):
        contact.probe((0.5, 0.1), "off")
    stepper.destroy()


def test_a_negative_dual_pressure_is_not_shown_as_a_pressure(shared_dir: pathlib.Path) -> None:
    """The block tilted on matching meshes (4 facets of 0.25 on y = 0): u_y = −θ(X − X_e),
    X_e = 0.625 the middle of the facet [0.5, 0.75], so the law's pressure ε_n θ (X − X_e)
    is positive on its far half only, where the P2 shape function of its vertex X = 0.5,
    (1 − s)(1 − 2s), is negative: λ = ∫ p N < 0 there and the dual-basis value p_k =
    λ_k / D_k is negative (−1.5 kPa at the caisson's edge of examples/goda_nonmatching.toml
    with ε_n = 1.01e11 N/m³, found by a user-path test). That is a weight of the
    projection, not a tension (the law ε_n⟨−g_n⟩₊ has none): ``pressure`` is 0 there
    (the law at the node, open), the raw value is ``pressure_dual``, whose ∫ is still
    the residual's (round-off)."""
    stepper = _two_blocks(shared_dir / "tilt.msh")
    contact = _provider(stepper)
    θ, X_e = 1e-4, 0.625
    stepper.u[1].interpolate(lambda x: np.stack([0 * x[0], -θ * (x[0] - X_e)]))
    nodes = SlavePoints.nodes(contact)
    state = nodes.evaluate(contact.interface_values(stepper.u))
    vertex = np.isclose(nodes.X[:, 0], 0.5)
    assert vertex.sum() == 1
    assert state["pressure_dual"][vertex][0] < -1e-3 * state["pressure_dual"].max()
    np.testing.assert_array_equal(state["pressure"], np.maximum(state["pressure_dual"], 0))
    assert state["pressure"][vertex][0] == 0.0 == state["law_pressure"][vertex][0]
    lam = contact.normal_forces(contact.interface_values(stepper.u))
    assert nodes.weights is not None
    assert nodes.weights @ state["pressure_dual"] == pytest.approx(lam.sum(), rel=1e-12)
    snap = contact.snapshot(stepper.u)  # static.npz's contact_c_pressure(_dual)
    assert snap["pressure"].min() == 0.0 > snap["pressure_dual"].min()
    stepper.destroy()


# --- a pushed block, through simulation.run ---------------------------------------

MU, WIDTH, HEIGHT, PENALTY = 0.6, 0.1, 0.05, 1e9
MASS = MATERIAL.density * WIDTH * HEIGHT
WEIGHT = MASS * G
PUSH = 1.5 * MU * WEIGHT
END = 0.3


def _pushed_mesh(path: pathlib.Path) -> pathlib.Path:
    """A 0.4 m base (20 elements) under the block (3 elements), meshed apart."""
    return rectangles(path, COMM, [Rectangle("base", -0.1, -0.05, 0.4, 0.05, 20, 2),
                                   Rectangle("block", -0.05, 0.0, WIDTH, HEIGHT, 3, 2)])


def _pushed_block(mesh: pathlib.Path, damping: Damping | None = None) -> ContactModel:
    """The block on the base (general pair, μ = MU), gravity, pushed by PUSH from t = 0."""
    pair = SurfacePair("c", "block", "base", "block_bottom", "base_top", PENALTY,
                       friction=MU)
    return ContactModel(read_mesh(mesh, COMM), [Body("base", MATERIAL),
                                                Body("block", MATERIAL)],
                        fixed=[Fixed("base_bottom")], gravity=(0.0, -G),
                        loads=[SurfaceLoad("block_left", (PUSH / HEIGHT, 0.0),
                                           lambda t: 1.0)],
                        damping=damping, surface_pairs=[pair])


@pytest.fixture(scope="module")
def pushed(folder: pathlib.Path) -> pathlib.Path:
    """A 0.1 m × 0.05 m block (3 elements) pushed by 1.5 μN along a 0.4 m base (20
    elements) for 0.3 s, probes at the middle of its bottom (a slave node above a
    master node at the start) and at its left corner."""
    from breakwater.run import simulation

    model = _pushed_block(_pushed_mesh(folder / "pushed.msh"), Damping(0.0, 1e-4))
    out = folder / "pushed"
    output = OutputSpec(out, field_interval=15, figures=False, progress=False,
                        probes=(ProbeSpec("mid", "block", (0.0, 0.0)),
                                ProbeSpec("base_mid", "base", (0.0, 0.0)),
                                ProbeSpec("corner", "block", (-0.05, 0.0))),
                        pair_probes=(PairProbeSpec("pmid", "c", (0.0, 0.0)),
                                     PairProbeSpec("pcorner", "c", (-0.05, 0.0))))
    summary = simulation.run(model, TimeSpec(dt=4e-3, end_time=END), output,
                             report=False)
    assert summary["finished"] is True
    return out


def test_pair_probe_of_a_sliding_block(pushed: pathlib.Path) -> None:
    """The probe's sides are the point probes (round-off); its slip is the slave's
    displacement less the master material point's, and grows at the rigid block's
    acceleration (F − μN)/m to 2 % after 0.02 s, over more than 5 master elements (0.1 m);
    its opening at the middle of the bottom is −(N/w)/ε_n: the pressure
    under the pushed block varies linearly (friction's moment: from 0.1 to 1.96 times
    the mean, measured), so its mean is at the middle; within 2 % once the vertical
    transient has died out (t > 0.15 s, as in test_surfacepair.test_finite_sliding;
    measured 1.3 %: the rest is the elastic bodies' own non-uniformity, which grows
    with ε_n w/E = 0.1 here; 7 % at ε_n = 1e10)."""
    h = read_history(pushed / "history.csv")
    t = h["t"]
    for pair, point in (("pmid", "mid"), ("pcorner", "corner")):
        for c in ("ux", "uy"):
            np.testing.assert_allclose(h[f"{pair}_slave_{c}"], h[f"{point}_{c}"],
                                       rtol=1e-12, atol=1e-18)
        np.testing.assert_allclose(h[f"{pair}_slip"],
                                   h[f"{pair}_slave_ux"] - h[f"{pair}_master_ux"],
                                   rtol=1e-12, atol=1e-18)
    # The base's material point under the middle at t = 0 is the base's point (0, 0).
    np.testing.assert_allclose(h["pmid_master_ux"], h["base_mid_ux"], rtol=1e-12, atol=1e-18)
    # The push acts at t = 0, so the block is held in its static state and released
    # (breakwater.statics.relaxation): the slip then grows at the rigid block's acceleration
    # (F − μN)/m. Its start carries GN22's first-step velocity error (a₀ of the
    # regularised law, README "general pairs"), so the acceleration is compared: a
    # quadratic fitted to the slip after 0.02 s, within 2 %.
    early = t > 0.02
    acceleration = 2 * np.polyfit(t[early], h["pmid_slip"][early], 2)[0]
    assert acceleration == pytest.approx((PUSH - MU * WEIGHT) / MASS, rel=0.02)
    assert h["pmid_slip"][-1] > 5 * 0.02
    late = t > 0.15
    δ = WEIGHT / WIDTH / PENALTY
    assert np.abs(h["pmid_opening"][late] / -δ - 1).max() < 0.02


def _simpson(path: pathlib.Path, step: int, name: str) -> tuple[float, float]:
    """Time and ∫ of a scalar field over the line mesh of a VTX file (P2 facets)."""
    import adios2

    with adios2.FileReader(str(path)) as r:
        x = r.read("geometry")[:, :2]
        cells = r.read("connectivity")  # VTK Lagrange curves: count, two ends, midpoint
        ends, mid = cells[:, 1:3], cells[:, 3]
        length = np.linalg.norm(x[ends[:, 1]] - x[ends[:, 0]], axis=1)
        t = float(r.read("step", step_selection=[step, 1])[0])
        f = r.read(name, step_selection=[step, 1])[:, 0]
        return t, float(np.sum(length / 6 * (f[ends[:, 0]] + 4 * f[mid] + f[ends[:, 1]])))


def test_contact_fields_of_a_general_pair(pushed: pathlib.Path) -> None:
    """``contact_c.bp`` holds the fields of a conforming pair on the slave surface, at
    its nodes; read back (serially: a file written on 2 ranks holds one block per
    rank), its pressure integrates to the history's normal resultant at every written
    time: Simpson's rule on the nodal values is Σ_k p_k ∫N_k, which the dual-basis
    field (:func:`breakwater.contact.slavepoints.nodal_pressure`) makes the residual's
    ∫p exactly; the history's y component differs from it by the master normal's tilt
    under the block's weight (measured at most 1.6e-7, checked to 1e-6). The whole bottom
    slides (|v_T| ≫ χ), so the friction traction integrates to −μ∫p (Coulomb;
    measured 5e-13, checked to 1e-9)."""
    path = pushed / "contact_c.bp"
    assert path.exists()
    if COMM.size > 1:
        return
    import adios2

    h = read_history(pushed / "history.csv")
    with adios2.FileReader(str(path)) as r:
        steps = r.num_steps()
        assert set(r.available_variables()) >= {"pressure", "gap", "slip", "slip_velocity",
                                                 "friction_traction"}
    assert steps == round(END / 4e-3) // 15 + 1
    checked = 0
    for k in range(steps):
        t, force = _simpson(path, k, "pressure")
        j = int(np.argmin(np.abs(h["t"] - t)))
        assert h["t"][j] == pytest.approx(t, rel=1e-12)
        assert force == pytest.approx(h["c_force_y"][j], rel=1e-6)
        checked += 1
        _, traction = _simpson(path, k, "friction_traction")
        if t > 0.05:
            assert traction == pytest.approx(-MU * force, rel=1e-9)
    assert checked >= 2


def test_snapshots_and_quality_of_a_general_pair(pushed: pathlib.Path) -> None:
    """The snapshots hold the slave surface's nodal arrays (at the peak, the last step:
    the pressure's mean over the bottom's equally spaced nodes is N/w within 2 %, its
    linear variation averaging out (measured 0.6 %), and every node's slip is the
    middle probe's to 1e-5: the block slides rigidly, up to its elastic strain
    (measured 6e-7)); the summary's
    ``contact_quality.c`` has the conforming pairs' keys, h the slave facets' length
    and the dynamic penetration the history's largest."""
    h = read_history(pushed / "history.csv")
    with np.load(pushed / "static.npz") as data:
        assert list(data["contacts"]) == ["c"]  # the pairs, in order: contact_<name>_*
        x = data["contact_c_x"]
        assert x.shape == (7, 2)  # 3 P2 facets
        np.testing.assert_allclose(x[:, 1], 0.0, atol=1e-15)
        assert np.all(np.diff(x[:, 0]) > 0)
        for key in ("normal", "gap", "slip", "pressure"):
            assert len(data[f"contact_c_{key}"]) == 7, key
    with np.load(pushed / "snapshot_max_ux.npz") as data:
        assert float(data["time"]) == pytest.approx(END)
        p = data["contact_c_pressure"]
        assert p.mean() == pytest.approx(WEIGHT / WIDTH, rel=0.02)
        np.testing.assert_allclose(data["contact_c_slip"], h["pmid_slip"][-1], rtol=1e-5)
    with open(pushed / "summary.json", encoding="utf-8") as f:
        summary = json.load(f)
    q = summary["contact_quality"]["c"]
    expected = quality.assess("c", 1.0, 1.0, (1.0, 1.0), 0.0, 1.0).as_dict()
    assert set(q) == set(expected)
    assert q["element_size"] == pytest.approx(WIDTH / 3, rel=1e-12)
    assert q["penalty_h_over_E"]["slave"] == pytest.approx(PENALTY * WIDTH / 3 / 1e9)
    steps = h["c_penetration"][1:]
    assert q["dynamic_penetration"] == pytest.approx(steps.max(), rel=1e-12)
    assert q["time_of_dynamic_penetration"] == pytest.approx(h["t"][1:][np.argmax(steps)])
    # The run starts from its static state (breakwater.statics.relaxation): the static
    # penetration is the first row's, and the verdict follows the report's criteria
    # (breakwater.outputs.quality): this stiff block on a stiff base settles by about its own
    # penetration, so the penalty is too soft by the settlement criterion.
    assert q["static_penetration"] == pytest.approx(h["c_penetration"][0], rel=1e-12)
    soft = (max(q["static_penetration"], q["dynamic_penetration"])
            > quality.MAX_PENETRATION_OVER_H * q["element_size"]
            or q["static_penetration_over_settlement"]
            > quality.MAX_PENETRATION_OVER_SETTLEMENT)
    stiff = max(q["penalty_h_over_E"].values()) > quality.MAX_STIFFNESS_RATIO
    assert q["verdict"] == {(False, False): "ok", (True, False): "too soft",
                            (False, True): "too stiff"}[(soft, stiff)]
    assert soft and not stiff


# --- the example through the command line ----------------------------------------

EXAMPLE = pathlib.Path(__file__).parents[1] / "examples" / "sliding_block" / "sliding_block.toml"


def test_example_with_a_pair_probe_and_figures(shared_dir: pathlib.Path) -> None:
    """The sliding block example (its pair probe ``corner`` on the general pair) runs
    through the command line with figures and ParaView fields: the pair probe's
    figures and the static pressure are drawn, and its slave side is the point probe
    at the same corner."""
    from breakwater import cli

    out = shared_dir / "run"
    assert cli.main(["run", str(EXAMPLE), "--out", str(out), "--no-progress", "--quiet",
                     "--set", "time.end_time=0.01", "--set", "output.field_interval=5",
                     "--set", "output.figures=true"]) == 0
    for name in ("pair_probes_ux.png", "pair_probes_uy.png", "static_pressure.png"):
        assert (out / "figures" / name).exists(), name
    assert (out / "contact_sliding.bp").exists()
    h = read_history(out / "history.csv")
    np.testing.assert_allclose(h["corner_slave_ux"], h["corner_ux"], rtol=1e-12, atol=1e-18)
    assert h["corner_slip"][-1] > 0
    with open(out / "summary.json", encoding="utf-8") as f:
        summary = json.load(f)
    assert summary["dynamic"]["residual_slip"] == pytest.approx(h["corner_slip"][-1])
    assert "sliding" in summary["contact_quality"]


def test_pair_probe_off_the_slave_surface_is_an_input_error(shared_dir: pathlib.Path
                                                            ) -> None:
    """A pair probe of a general pair is placed once the pair is built (after the
    static state): a point off its slave surface still exits 2 (a bad input, as the
    case errors found before a run), with the message, not 1 (a failed run)."""
    from breakwater import cli

    assert cli.main(["run", str(EXAMPLE), "--out", str(shared_dir / "off"), "--no-progress",
                     "--quiet", "--set", "time.end_time=0.005", "--set",
                     'output.pair_probes.corner={pair="sliding", point=[5.0, 5.0]}']) == 2


# --- resume -------------------------------------------------------------------------

def test_resume_keeps_the_general_outputs(shared_dir: pathlib.Path,
                                          monkeypatch: pytest.MonkeyPatch) -> None:
    """A run with a general pair's probe, fields and quality report, killed after its
    checkpoint, resumes to the uninterrupted history of the probe (serially bit for
    bit; on 2 ranks within the 1e-7 of test_surfacepair's resume test, whose reasons
    hold here) and the same quality report; the fields written before the kill are
    set aside as ``contact_c.part1.bp``."""
    from breakwater.run import simulation

    mesh = _pushed_mesh(shared_dir / "resume.msh")

    def run(directory: pathlib.Path, **kwargs: object) -> dict:
        model = _pushed_block(mesh)
        output = OutputSpec(directory, field_interval=4, figures=False, progress=False,
                            checkpoint_interval=5,
                            probes=(ProbeSpec("corner", "block", (-0.05, 0.0)),),
                            pair_probes=(PairProbeSpec("pmid", "c", (0.0, 0.0)),))
        return simulation.run(model, TimeSpec(dt=4e-3, end_time=0.1), output,
                              report=False, **kwargs)  # type: ignore[arg-type]

    full = run(shared_dir / "full")
    run_killed_at(run, shared_dir / "resumed", 0.07, monkeypatch)
    resumed = run(shared_dir / "resumed", resume=True)
    assert resumed["finished"] is True
    assert (shared_dir / "resumed" / "contact_c.part1.bp").exists()
    assert (shared_dir / "resumed" / "contact_c.bp").exists()
    a = read_history(shared_dir / "full" / "history.csv")
    b = read_history(shared_dir / "resumed" / "history.csv")
    np.testing.assert_array_equal(a["t"], b["t"])
    rtol = 1e-12 if COMM.size == 1 else 1e-7
    for key in ("pmid_slip", "pmid_opening", "pmid_master_ux", "c_penetration"):
        scale = np.abs(a[key]).max()
        assert np.abs(a[key] - b[key]).max() <= rtol * scale, key
    qa, qb = full["contact_quality"]["c"], resumed["contact_quality"]["c"]
    assert qa["static_penetration"] == qb["static_penetration"]
    assert qa["element_size"] == qb["element_size"]
    assert qb["dynamic_penetration"] == pytest.approx(qa["dynamic_penetration"], rel=rtol)
