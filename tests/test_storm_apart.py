"""Storm waves that slide a caisson by metres: ``examples/prototype/storm_apart.toml``.

The prototype caisson (B = 30 m, 19.5 m high, W' = 7.68 MN/m) meshed apart from its
mound, a general pair under its base (finite sliding, finite rotations), μ = 0.35, two
waves H = 12 m then 14 m (T = 14 s) with adaptive steps. At the second wave's onset one
step's Newton used to cycle between overshoots (a stick/slip change inside the step) at
every step size down to the smallest: the run failed at t = 16.06 s (issue 24's note)
until the interface Newton's rescue (its overshooting steps halved,
:mod:`breakwater.stepping.interfacenewton`; 1 rescue, 16 halvings, 3582 Newton
iterations). Since the slip guard lands slips on the friction law's curve
(:mod:`breakwater.contact.guardkernels`) that step converges at once: no rescue, 2179
iterations, the same sliding to 1e-10. The rescue keeps its own test
(``tests/test_newton_rescue.py``). About 10 s of CPU.
"""

from __future__ import annotations

import pathlib

import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from breakwater.run import simulation

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
    # No cut-back, and no rescue: the landings on the law's curve converge the step
    # whose Newton cycled (measured: 0 and 0; 1 rescue with 16 halvings before them).
    assert solver["cutbacks"] == 0 and solver["newton_rescues"] == 0
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
