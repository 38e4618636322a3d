"""Storm waves that slide a caisson by metres: ``examples/prototype/storm_apart.toml``.

The prototype caisson (B = 30 m, 19.5 m high, W' = 7.68 MN/m) meshed apart from its
mound, a general pair under its base (finite sliding, finite rotations), μ = 0.35, two
waves H = 12 m then 14 m (T = 14 s) with adaptive steps. At the second wave's onset one
step's Newton cycles between overshoots (a stick/slip change inside the step) at every
step size down to the smallest; the interface Newton's rescue (its overshooting steps
halved: :mod:`breakwater.stepping.interfacenewton`) converges it. Before the rescue the
run failed at t = 16.06 s (issue 24's note); about 10 s of CPU.
"""

from __future__ import annotations

import pathlib

import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from breakwater.run import simulation
from breakwater.run.simulation import SimulationFailed
from breakwater.stepping import interfacenewton

EXAMPLE = pathlib.Path(__file__).resolve().parents[1] / "examples" / "prototype" \
    / "storm_apart.toml"
COMM = MPI.COMM_WORLD


def _run(directory: pathlib.Path) -> dict:
    from breakwater.casefile.case import load_case

    built = load_case(EXAMPLE, ["output.figures=false", "output.field_interval=0",
                                f"output.directory={directory.as_posix()}"]).build(COMM)
    return simulation.run(built.model, built.time, built.output, extra_summary=built.extra,
                          report=False)


@pytest.mark.timeout(300)
def test_storm_slides_the_caisson_apart_by_metres(shared_dir: pathlib.Path) -> None:
    summary = _run(shared_dir / "apart")
    solver, storm = summary["solver"], summary["storm"]
    assert summary["finished"] and storm["waves_finished"] == 2
    assert solver["cutbacks"] == 0 and solver["newton_rescues"] >= 1  # measured 1
    assert solver["newton_halvings"] >= 1  # the rescue halved at least one step
    # The second wave slides the caisson 2.58 m: against the rigid block under the same
    # wave loads (Shimosako & Takahashi's model, breakwater.storms.rigid: the FE model's
    # M, W' and μ), 2.611 m. At metres of sliding the mound's elastic deformation (a few
    # mm: the first wave's 20.7 against 15.3 mm) is below 0.3 %, and the adaptive steps'
    # tolerance (1e-2 of the step's increment) about 1 %: measured −1.3 % (fixed 0.02 s
    # steps: +0.5 %, docs/storms.md). Bound 3 %.
    assert storm["most_sliding"]["wave"] == 2
    fe, rigid = storm["most_sliding"]["sliding"], storm["rigid"]["sliding"][1]
    assert rigid > 2.5
    assert fe == pytest.approx(rigid, rel=0.03)


@pytest.mark.serial
@pytest.mark.timeout(300)
def test_without_the_rescue_the_storm_fails(shared_dir: pathlib.Path,
                                            monkeypatch: pytest.MonkeyPatch) -> None:
    # No halving: the rescue is the plain Newton again, and the run stops at the second
    # wave's onset, as it did before the rescue existed.
    monkeypatch.setattr(interfacenewton, "HALVINGS", 0)
    with pytest.raises(SimulationFailed, match=r"did not converge at the smallest adaptive "
                       r"step .* again with its overshooting steps halved"):
        _run(shared_dir / "plain")
