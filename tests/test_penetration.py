"""Penetration a general pair's search cannot see (breakwater.contact.penetration).

A general pair presses a slave node only while the search finds it within its radius r
of the master surface (the longest master facet). A block thrown at 20 m/s onto the
0.1 m base of tests/bad_cases/run/p2_tunnelling_block.toml with Δt = 1 ms moves 20 mm
per step, twice r = 10 mm: it used to end its first step 20 mm inside the base, unseen,
and go through it with a contact force of zero (exit 0). The step is now cut back until
the contact sees it; a mesh that starts overlapped beyond r is refused by the static
stage, the pair's static check (tests/bad_cases/run/p3_overlapping_start.toml).
"""

from __future__ import annotations

import pathlib

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from breakwater.meshes.apart import Rectangle, rectangles

from breakwater import cli
from breakwater.common.errors import MeshError
from breakwater.common.files import read_history
from breakwater.contact.penetration import (
    _motion_bound,
    allowed_depth,
    meshed_overlap,
    screen_bound,
    step_penetration,
)
from breakwater.contact.surfaces import Surface, SurfacePair
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, Fixed, Material
from breakwater.statics.initial import STICK_BAND
from breakwater.statics.pseudostep import PseudoStepper
from breakwater.stepping.gn22 import GN22

COMM = MPI.COMM_WORLD
RUNS = pathlib.Path(__file__).parent / "bad_cases" / "run"


# --- the step check on a flat master, by hand ------------------------------------------

# Two straight master facets on y = 0, x ∈ [0, 2], oriented so that (t_y, −t_x) = +y is
# outward (each facet runs from right to left), their cells 0.3 m high below them
# (centroid at y = −0.1): the pair sees min(r, 0.3) = 0.3 m deep with r = 1 m.
MASTER = Surface(X=np.array([[[1.0, 0.0], [0.0, 0.0]], [[2.0, 0.0], [1.0, 0.0]]]),
                 dofs=-np.ones((2, 2, 2), np.int64),
                 interior=np.array([[0.5, -0.1], [1.5, -0.1]]))
PAIR = SurfacePair("c", "slave", "master", "s", "m", 1e9)
R = 1.0


def _check(start: tuple[float, float], move: tuple[float, float], facet: int,
           xi: float = 0.0) -> str | None:
    """step_penetration of one slave node from ``start`` moved by ``move`` (master still)."""
    node_X = np.array([start])
    node_pos = np.array([[0, 1]])
    pos_m = -np.ones((2, 2, 2), np.int64)  # the master's Dirichlet entries: the trailing 0
    u0 = np.zeros(3)
    u1 = np.array([*move, 0.0])
    N0 = np.array([[0.5 * (1 - xi), 0.5 * (1 + xi)]])
    t0 = np.array([[-1.0, 0.0]])
    start_data = (np.array([facet]), N0, t0, np.array([facet >= 0]))
    return step_penetration(PAIR, R, allowed_depth(MASTER, R), start_data, node_X, node_pos,
                            MASTER.X, pos_m, u0, u1)[0]


def test_allowed_depth_is_the_radius_or_the_element() -> None:
    # The cells' centroids are 0.1 m below the facets: height 0.3 m.
    assert allowed_depth(MASTER, 1.0) == pytest.approx([0.3, 0.3])
    assert allowed_depth(MASTER, 0.2) == pytest.approx([0.2, 0.2])


def test_step_check_depth_motion_and_far_nodes() -> None:
    # A node 1 mm above facet 0, projected there at the start of the step.
    assert _check((0.5, 0.001), (0.0, -0.25), 0) is None  # ends 0.249 m deep < 0.3 m
    deep = _check((0.5, 0.001), (0.0, -0.35), 0)           # 0.349 m deep > 0.3 m
    assert deep is not None and "ends the step 0.349 m inside the master 'master'" in deep
    assert "contact 'c'" in deep
    # Sliding along the master: 0.9 r per step is seen, 1.2 r is not.
    assert _check((0.5, 0.001), (0.9, 0.0), 0) is None
    fast = _check((0.5, 0.001), (1.2, 0.0), 0)
    assert fast is not None and "moves 1.2 m relative to the master" in fast
    # A node 5 m above the surface (no projection within r): moving 2 m in a step
    # cannot reach the surface; moving 6 m could pass through it.
    assert _check((1.0, 5.0), (0.0, -2.0), -1) is None
    far = _check((1.0, 5.0), (0.0, -6.0), -1)
    assert far is not None and "more than its distance 5 m from the master surface" in far


@pytest.mark.parametrize("seed", range(4))
def test_screen_bound_is_the_motion_bound(seed: int) -> None:
    """StepCheck's compiled screen bound equals ``_motion_bound``'s largest entry.

    Random motions of 7 slave nodes and 5 quadratic master facets, some positions
    Dirichlet (−1: u's trailing 0); the same sums in another order: 1e-14 relative.
    """
    rng = np.random.default_rng(seed)
    n = 40
    u0, u1 = np.append(rng.normal(size=n), 0.0), np.append(rng.normal(size=n), 0.0)
    node_pos = rng.integers(-1, n, size=(7, 2))
    pos_m = rng.integers(-1, n, size=(5, 3, 2))
    expected = _motion_bound(u1[node_pos] - u0[node_pos], u1[pos_m] - u0[pos_m])[0].max()
    assert screen_bound(u0, u1, node_pos, pos_m) == pytest.approx(expected, rel=1e-14)
    # No master facet: the nodes' own motion.
    assert screen_bound(u0, u1, node_pos, pos_m[:0]) == pytest.approx(
        np.linalg.norm(u1[node_pos] - u0[node_pos], axis=1).max(), rel=1e-14)


# --- the tunnelling block, through the command line -------------------------------------

def test_tunnelling_block_is_cut_back_and_caught(shared_dir: pathlib.Path) -> None:
    """The 20 m/s block with Δt = 1 ms and the default 4 cut-backs: the first step is
    halved twice (10 mm, then 5 mm per step) and the contact stops the block.

    Reference: a rigid block of mass m = ρ·0.2·0.1 at v = 20 m/s on a penalty ε_n over
    the width w = 0.2 m stops within g = v sqrt(m/(ε_n w)) = 1.36 mm (½ ε_n w g² =
    ½ m v²; the elastic bodies take part of the energy): the largest penetration must be
    of that order, and well within what the pair sees (r = 10 mm). Without the check
    the block ended the first step 20 mm inside the base with a contact force of zero
    and was 80 mm below the base's top at 4 ms."""
    out = shared_dir / "out"
    case = RUNS / "p2_tunnelling_block.toml"
    assert cli.main(["run", str(case), "--out", str(out), "--quiet", "--no-progress",
                     "--set", "time.max_cutbacks=4"]) == 0
    h = read_history(out / "history.csv")
    assert h["dt"][1] == pytest.approx(2.5e-4)  # the first step, halved twice
    assert h["sliding_force_y"].max() > 1e6     # N/m: the impact (measured 8.1e6)
    m, v, eps, w = 2314.0 * 0.2 * 0.1, 20.0, 5.0e10, 0.2
    g = v * np.sqrt(m / (eps * w))
    assert 0.3 * g < h["sliding_penetration"].max() < 2 * g  # measured 1.05 mm
    assert h["corner_uy"][-1] > 0  # bounced back up, not through the base


# --- the initial overlap ---------------------------------------------------------------

def test_a_meshed_gap_is_measured_on_the_pairs_own_surfaces(
        shared_dir: pathlib.Path, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    """p14 (a 2-D block meshed 2 mm above its base): the run warns as before, the gaps
    measured on the surfaces the pair gathered when it was built: meshed_gap2d gathers
    nothing (it gathered both surfaces again, two collective allgathers, at every run's
    start)."""
    from breakwater.contact import penetration
    from breakwater.run import begin

    gathered: list[str] = []
    real_gather, real_gap = penetration.gather_surface, begin.meshed_gap2d

    def counted(*args: object) -> object:
        gathered.append(str(args[2]))  # the body
        return real_gather(*args)  # type: ignore[arg-type]

    during: list[int] = []

    def watched(*args: object) -> object:
        before = len(gathered)
        line = real_gap(*args)  # type: ignore[arg-type]
        during.append(len(gathered) - before)
        return line

    monkeypatch.setattr(penetration, "gather_surface", counted)
    monkeypatch.setattr(begin, "meshed_gap2d", watched)
    case = RUNS / "p14_meshed_gap_2d.toml"
    assert cli.main(["run", str(case), "--out", str(shared_dir / "out"), "--quiet",
                     "--no-progress"]) == 0
    err = capsys.readouterr().err
    phrase = case.read_text().splitlines()[0].removeprefix("# expect: ")
    if COMM.rank == 0:  # rank 0 prints
        assert err.count(phrase) == 1, err
    assert during == [0]  # one pair, no gather
    assert gathered  # (the counting sees the other checks' gathers)


@pytest.mark.parametrize("sunk", [0.0, 1e-3, 0.03], ids=["touching", "1mm", "30mm"])
def test_initial_overlap(sunk: float, shared_dir: pathlib.Path) -> None:
    """A block meshed ``sunk`` into its base (10 mm facets: r = 10 mm, cells 20 mm high):
    touching or 1 mm in is a start the penalty resolves (the static state pushes it
    out); 30 mm, beyond r, is refused with the pair, the node and the depth by the
    pair's static check (Pair.static_check), which every GN22 stepper runs for its pairs
    when it is built: the static stage's, before it looks for the initial state, and one
    built directly from Python."""
    mesh = rectangles(shared_dir / "overlap.msh", COMM,
                      [Rectangle("base", -0.2, -0.1, 0.4, 0.1, 40, 5),
                       Rectangle("block", -0.1, -sunk, 0.2, 0.1, 7, 4)])
    steel = Material(7800.0, 0.3, young_modulus=2e11)
    pair = SurfacePair("sliding", "block", "base", "block_bottom", "base_top", 1e10)
    model = ContactModel(read_mesh(mesh, COMM), [Body("block", steel), Body("base", steel)],
                         fixed=[Fixed("base_bottom")], surface_pairs=[pair])
    message = (r"contact 'sliding': slave node at \(-0\.1, -0\.03\) m starts inside the "
               r"master 'base' or on its boundary, 0\.03 m from its contact surface")
    if sunk < 0.01:
        stepper = GN22(model, 1e-3)
        assert [p.static_check() for p in stepper.contacts] == [None]
        stepper.destroy()
        # Touching: nothing to say. 1 mm in (a tenth of the 10 mm facets, above OVERLAP):
        # the run warns, naming the depth and the block's bottom nodes inside the base
        # (its 7 quadratic facets: 2·7 + 1 = 15 nodes); before, the static state pushed
        # the block out in silence, its displacements and settlement holding the 1 mm.
        warning = meshed_overlap(model, pair)
        if sunk == 0.0:
            assert warning is None
        else:
            assert warning is not None and warning.startswith(
                "contact 'sliding': the meshes overlap: 15 slave node(s) start inside the "
                "master 'base', the deepest 0.001 m at (")
        return
    with pytest.raises(MeshError, match=message):  # any stepper built on the model
        GN22(model, 1e-3)
    with pytest.raises(MeshError, match=message):  # the static stage
        PseudoStepper(model, None, STICK_BAND)
