"""More than two bodies: three stacked blocks, two contact pairs with different friction.

``block0`` (bottom, fixed base) carries ``block1``, which carries ``block2``; ``block1`` is
the slave of ``joint0`` and the master of ``joint1``. Stiff blocks (the rigid limit, as in
``test_friction.py``), a horizontal pulse on the top block's left side whose peak is 1.5 ×
μ₁ W₂ (W_k the weight per unit length of block k): Coulomb's law lets the top block slide
on ``joint1``, while ``joint0`` (μ₀ (W₁ + W₂) is larger than the μ₁ W₂ that ``joint1`` can
pass down) sticks. Serial and under MPI.
"""

from __future__ import annotations

import pathlib

import numpy as np
import pytest
from blocks import stacked_blocks
from mpi4py import MPI

from breakwater.config.runspec import OutputSpec, PairProbeSpec, TimeSpec
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, ContactPair, Fixed, Material, SurfaceLoad
from breakwater.outputs.writers import read_history
from breakwater.run import simulation

COMM = MPI.COMM_WORLD
WIDTH, HEIGHTS = 0.4, (0.2, 0.15, 0.1)   # m
DENSITIES = (1800.0, 2300.0, 2500.0)     # kg/m³
G = 9.81
μ0, μ1 = 0.3, 0.6                        # joint0 (block1 on block0), joint1 (block2 on block1)
W = [ρ * G * WIDTH * H for ρ, H in zip(DENSITIES, HEIGHTS, strict=True)]  # N/m
PEAK = 1.5 * μ1 * W[2]                   # N/m, the pulse's peak force on block2
PULSE, DT = 4e-3, 1e-4                   # s


def test_three_bodies_two_pairs(folder: pathlib.Path, shared_dir: pathlib.Path) -> None:
    # The lower joint can pass on up to μ₀ (W₁ + W₂) = 700 N/m; the upper one at most
    # μ₁ W₂ = 589 N/m: block1 cannot slide in the rigid limit.
    assert μ0 * (W[1] + W[2]) > μ1 * W[2]
    path = stacked_blocks(folder / "three.msh", COMM, WIDTH, HEIGHTS, h=0.05)

    def pulse(t: float) -> float:
        s = t / PULSE
        return PEAK / HEIGHTS[2] * max(0.0, 1.0 - abs(2.0 * s - 1.0)) if 0 <= s <= 1 else 0.0

    bodies = [Body(f"block{k}", Material(ρ, 0.2, young_modulus=1e11))
              for k, ρ in enumerate(DENSITIES)]
    model = ContactModel(read_mesh(path, COMM), bodies,
                         [ContactPair("joint0", "block1", "block0", 1e13, friction=μ0),
                          ContactPair("joint1", "block2", "block1", 1e13, friction=μ1)],
                         [Fixed("base")], [SurfaceLoad("left2", (1.0, 0.0), pulse)],
                         gravity=(0.0, -G))
    y0, y1 = HEIGHTS[0], HEIGHTS[0] + HEIGHTS[1]
    output = OutputSpec(shared_dir, field_interval=10, figures=False, progress=False,
                        pair_probes=(PairProbeSpec("corner0", 0, (-WIDTH / 2, y0)),
                                     PairProbeSpec("corner1", 1, (-WIDTH / 2, y1))))
    summary = simulation.run(model, TimeSpec(dt=DT, end_time=1.5 * PULSE), output)
    assert summary["finished"] is True
    h = read_history(shared_dir / "history.csv")

    # Static: each joint carries the weight above it. The static solve stops at a
    # residual of 1e-9 of the load norm, so 1e-6 relative is safe.
    assert h["joint1_normal_force"][0] == pytest.approx(W[2], rel=1e-6)
    assert h["joint0_normal_force"][0] == pytest.approx(W[1] + W[2], rel=1e-6)
    for k in (0, 1):
        assert h[f"joint{k}_contact_length"][0] == pytest.approx(WIDTH, rel=1e-12)
    # The summary's static weight of the first pair is that of its slave and of the
    # block resting on it.
    assert summary["static"]["weight"] == pytest.approx(W[1] + W[2], rel=1e-9)
    assert summary["static"]["resultant_over_weight"] == pytest.approx(1.0, rel=1e-6)

    # While the pulse exceeds μ₁ W₂ the top block slides: the whole joint1 is at the
    # Coulomb limit, its shear resultant μ₁ times its normal resultant (the regularised
    # sign is ±1 to χ²/2v² at the sliding nodes; 1e-6 allows for the nodes at the
    # instants where the slip starts and stops).
    force = np.array([pulse(t) * HEIGHTS[2] for t in h["t"]])
    sliding = force > 1.05 * μ1 * W[2]
    assert sliding.sum() >= 5
    np.testing.assert_allclose(np.abs(h["joint1_tangential_force"][sliding]),
                               μ1 * h["joint1_normal_force"][sliding], rtol=1e-6)
    # joint0 stays below its limit and does not slip: its slip is elastic, of order
    # (μ₁ W₂ / width) / G × the block heights ≈ 1e-8 m (measured 1.2e-8 m), against a
    # slide of the top block of 2.8e-6 m; 1e-2 of the slide separates the two.
    assert np.all(np.abs(h["joint0_tangential_force"]) < μ0 * h["joint0_normal_force"])
    slide = abs(h["corner1_slip"][-1] - h["corner1_slip"][0])
    assert slide > 1e-6
    assert np.abs(h["corner0_slip"] - h["corner0_slip"][0]).max() < 1e-2 * slide

    # Both pairs are reported and written for ParaView.
    assert set(summary["contact_quality"]) == {"joint0", "joint1"}
    for name in ("fields_block0.bp", "fields_block1.bp", "fields_block2.bp",
                 "contact_joint0.bp", "contact_joint1.bp"):
        assert (shared_dir / name).exists(), name
