"""The contact quality report (breakwater.outputs.quality): pure functions of numbers.

Reference values are computed here from the definitions in the module docstring:
penetration δ = max ⟨−g_n⟩₊, settlement s = |mean(½(u_s + u_m)·n)|, stiffness ratio
ε_n h / E, thresholds δ ≤ 1% h, δ_static ≤ 10% s, ε_n h / E_soft ≤ 1000.
"""

from __future__ import annotations

import pathlib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from mpi4py import MPI

from breakwater.outputs import quality

COMM = MPI.COMM_WORLD


def test_max_penetration() -> None:
    assert quality.max_penetration(np.array([0.1, -2e-3, -1e-3, 0.0])) == 2e-3
    assert quality.max_penetration(np.array([0.1, 0.0, 3.0])) == 0.0  # open or touching
    assert quality.max_penetration(np.array([])) == 0.0


def test_settlement() -> None:
    # Both sides move down by s, the slave δ more (it penetrates): the interface's
    # mean normal displacement is s + δ/2, whatever the direction of the interface.
    s, δ = 3e-4, 2e-5
    n = np.tile([0.0, 1.0], (5, 1))
    u_m = -s * n
    u_s = u_m - δ * n
    assert quality.settlement(u_s, u_m, n) == pytest.approx(s + δ / 2, rel=1e-14)
    θ = 0.3  # rotate everything: same value (rotation invariance, rel. round-off)
    R = np.array([[np.cos(θ), -np.sin(θ)], [np.sin(θ), np.cos(θ)]])
    assert quality.settlement(u_s @ R.T, u_m @ R.T, n @ R.T) == \
        pytest.approx(s + δ / 2, rel=1e-14)
    # A tangential motion does not settle.
    t = np.tile([1.0, 0.0], (5, 1))
    assert quality.settlement(1e-3 * t, 1e-3 * t, n) == 0.0


def test_stiffness_ratio() -> None:
    assert quality.stiffness_ratio(1e10, 0.25, 1e8) == pytest.approx(25.0, rel=1e-15)


def _goda() -> dict:
    """Goda-like numbers (the paper's §5-5.4): p = ρ g H = 2314·9.81·0.202 Pa, ε_n = 5e8 N/m³."""
    p, ε = 2314.0 * 9.81 * 0.202, 5e8
    E_mound = 2 * 2.3e6 * 1.25          # E = 2G(1 + ν), ν = 0.25
    E_caisson = 2 * 2e9 * 1.2           # ν = 0.2
    return {"name": "interface", "penalty": ε, "element_size": 0.0265,
            "young_moduli": (E_caisson, E_mound), "static_penetration": p / ε,
            "settlement_": 1.3e-4}


def test_assess_ok_on_the_goda_numbers() -> None:
    args = _goda()
    q = quality.assess(**args)
    assert q.verdict == "ok" and q.issues == () and q.warnings == ()
    d = q.as_dict()
    h, ε = args["element_size"], args["penalty"]
    assert d["static_penetration_over_h"] == pytest.approx(2314 * 9.81 * 0.202 / ε / h,
                                                           rel=1e-14)
    assert d["penalty_h_over_E"]["master"] == pytest.approx(ε * h / (2 * 2.3e6 * 1.25),
                                                            rel=1e-14)
    assert d["dynamic_penetration"] is None and d["dynamic_penetration_over_h"] is None
    low, high = d["suggested_penalty"]
    assert low < ε < high
    assert high == pytest.approx(1e3 * 2 * 2.3e6 * 1.25 / h, rel=1e-14)


def test_assess_too_soft_by_element_size() -> None:
    # A dynamic penetration of 2% h: too soft, with the time in the message.
    args = _goda()
    h = args["element_size"]
    q = quality.assess(**args, dynamic_penetration=0.02 * h, time_of_dynamic_penetration=0.032)
    assert q.issues == ("dynamic_penetration_over_h",)
    assert q.verdict == "too soft"
    assert "t = 0.032 s" in q.warnings[0] and "too soft" in q.warnings[0]
    # Twice the allowed penetration (r = 2): with δ ∝ ε_n^(-½) (a stiff body's edge, the
    # slowest fall) and the margin 0.8, the lower end is ε_n (2 / 0.8)².
    low, _ = q.suggested_penalty
    assert low == pytest.approx((2 / 0.8) ** 2 * args["penalty"], rel=1e-12)


def test_assess_too_soft_by_settlement() -> None:
    # δ = 20% of s (s includes at most δ/2): the bodies' own settlement is s_b ≥ s − δ/2
    # and δ' = 10% (s_b + δ'/2) allows δ' = 0.1 s_b / 0.95: r = δ / δ', and the lower end
    # ε_n (r / 0.8)² (δ ∝ ε_n^(-½), margin 0.8).
    args = {**_goda(), "static_penetration": 2.6e-5, "settlement_": 1.3e-4}
    q = quality.assess(**args)
    assert q.issues == ("penetration_over_settlement",)
    low, _ = q.suggested_penalty
    s_b = 1.3e-4 - 1.3e-5
    δ_new = 0.1 * s_b / 0.95
    assert low == pytest.approx(args["penalty"] * (2.6e-5 / δ_new / 0.8) ** 2, rel=1e-12)


# examples/goda_nonmatching.toml run to t = 3e-4 s at three penalties (this branch,
# before the fix of the suggestion): ε_n (N/m³), static penetration δ (m), settlement s
# (m), h = 0.014643 m, E = 4.8e9 (caisson), 5.694e6 Pa (mound); and the run at the
# suggestion of the fix, 2.87e9 (a run of its own, not used to make the rule).
GODA_NONMATCHING = [(5.0e8, 2.688529885456801e-05, 1.4687429490628853e-04),
                    (9.58e8, 1.8607454875949045e-05, 1.4389404659796766e-04),
                    (1.01e11, 1.9496820439679265e-06, 1.3803466005894938e-04)]
AT_THE_SUGGESTION = (2.87e9, 1.069846323148152e-05, 1.4130525081243047e-04)


def test_the_suggestion_of_a_general_pair_is_then_accepted() -> None:
    # The 1/ε_n rule suggested 9.57e8 at ε_n = 5e8, and the run at 9.58e8 was still too
    # soft (δ = 1.86e-5 > 10 % of s = 1.44e-5: δ fell as ε_n^-0.57, the caisson's edge).
    def at(ε: float, δ: float, s: float) -> quality.ContactQuality:
        return quality.assess("interface", ε, 0.014643, (4.8e9, 5.694e6), δ, s)

    runs = [at(*run) for run in GODA_NONMATCHING]
    assert [q.verdict for q in runs] == ["too soft", "too soft", "ok"]
    low, high = runs[0].suggested_penalty
    assert 9.58e8 < low < high  # above the penalty measured too soft
    # The measured exponents, between the runs, and the penetration they give at low:
    (ε0, δ0, s0), (ε1, δ1, _), (ε2, δ2, _) = GODA_NONMATCHING
    for α in (np.log(δ0 / δ1) / np.log(ε1 / ε0), np.log(δ1 / δ2) / np.log(ε2 / ε1)):
        δ = δ0 * (ε0 / low) ** α
        assert at(low, δ, s0 - (δ0 - δ) / 2).verdict == "ok"  # settlement: less δ/2
    # And the run: 2.87e9 (the suggestion 2.86e9 rounded up) passed, 7.6 % of s.
    assert low <= AT_THE_SUGGESTION[0] and at(*AT_THE_SUGGESTION).verdict == "ok"


def test_assess_too_stiff() -> None:
    # ε_n h / E_soft = 2000 > 1000.
    args = _goda()
    E_soft = min(args["young_moduli"])
    ε = 2000 * E_soft / args["element_size"]
    q = quality.assess(**{**args, "penalty": ε,
                          "static_penetration": args["static_penetration"] * 5e8 / ε})
    assert q.issues == ("stiff",) and q.verdict == "too stiff"
    assert "conditioning" in q.warnings[0]
    assert q.suggested_penalty[1] == pytest.approx(ε / 2, rel=1e-12)


def test_assess_both() -> None:
    # A tiny settlement (rigid bodies) and a stiff penalty: both criteria fail, and no
    # penalty meets both (the advice says to refine the mesh).
    q = quality.assess("p", 1e14, 0.01, (1e8, 1e8), 1e-7, 2e-7)
    assert set(q.issues) == {"penetration_over_settlement", "stiff"}
    assert q.verdict == "too soft and too stiff"
    assert "refine the mesh" in q.warnings[0]


@settings(max_examples=300, deadline=None)
@given(ε=st.floats(1e5, 1e14), h=st.floats(1e-3, 1.0), E=st.floats(1e5, 1e11),
       p=st.floats(1.0, 1e6), s_b=st.floats(1e-7, 1e-2), dyn=st.floats(1.0, 20.0),
       α=st.floats(0.5, 1.0), κ=st.floats(0.05, 1.0))
def test_range_matches_verdict(ε: float, h: float, E: float, p: float, s_b: float,
                               dyn: float, α: float, κ: float) -> None:
    # Whatever the numbers, the current penalty is inside the suggested range exactly
    # when it passes, and a penalty inside the range computed at another one passes:
    # the largest penetrations fall as ε_n^-α, α from ½ (a stiff body's edge) to 1
    # (a smooth pressure), at fixed forces (static p, dynamic dyn·p) and bodies'
    # settlement s_b, the settlement holding κδ/2 (the mean penetration's half).
    def at(penalty: float) -> quality.ContactQuality:
        δ = p / 1e9 * (1e9 / penalty) ** α
        return quality.assess("p", penalty, h, (E, 3 * E), δ, s_b + κ * δ / 2, dyn * δ,
                              0.0)

    # Margins of 1e-6: s_b is recovered as s − δ/2, which loses up to 1e-16 δ/s_b ≤
    # 1e-8 (δ ≤ 10 m, s_b ≥ 1e-7 m here) to cancellation.
    q = at(ε)
    low, high = q.suggested_penalty
    if low * (1 + 1e-6) < ε < high * (1 - 1e-6):
        assert q.verdict == "ok"
    elif not low * (1 - 1e-6) < ε < high * (1 + 1e-6):
        assert q.verdict != "ok"
    if low < high * (1 - 1e-5):
        assert at(np.sqrt(low * high)).verdict == "ok"
        assert at(low * (1 + 1e-6)).verdict == "ok"
        assert at(high * (1 - 1e-6)).verdict == "ok"
    assert "stiff" in at(high * (1 + 1e-6)).verdict


def _graded_blocks(path: pathlib.Path, ratio: float) -> pathlib.Path:
    """Block ``a`` on block ``b`` (both 1 m wide, ``b`` 0.5 m high), meshed by gmsh.

    ``a``'s top slopes from 0.2 m high at its left (x = −0.5) to 0.6 m at its right, and
    the interface has 10 facets in a geometric progression of ``ratio``, the finest at
    the right end. Physical names as :func:`blocks.two_rectangles` (``a``, ``b``,
    ``interface``, ``b_bottom``).
    """
    import gmsh
    from breakwater.meshes import gmsh_session

    from breakwater.common.parallel import on_rank_zero

    def build() -> None:
        with gmsh_session():
            geo = gmsh.model.geo
            p = [geo.addPoint(x, y, 0, 0.1) for x, y in
                 ((-0.5, 0.0), (0.5, 0.0), (0.5, 0.5), (-0.5, 0.5), (0.5, 1.1), (-0.5, 0.7))]
            bottom, right, itf, left = (geo.addLine(p[0], p[1]), geo.addLine(p[1], p[2]),
                                        geo.addLine(p[3], p[2]), geo.addLine(p[3], p[0]))
            a_right, a_top, a_left = (geo.addLine(p[2], p[4]), geo.addLine(p[4], p[5]),
                                      geo.addLine(p[5], p[3]))
            sb = geo.addPlaneSurface([geo.addCurveLoop([bottom, right, -itf, left])])
            sa = geo.addPlaneSurface([geo.addCurveLoop([itf, a_right, a_top, a_left])])
            geo.synchronize()
            # From p[3] (left) to p[2] (right): each facet 1/ratio of the one before.
            gmsh.model.mesh.setTransfiniteCurve(itf, 11, "Progression", 1 / ratio)
            for dim, tags, name in ((2, [sa], "a"), (2, [sb], "b"), (1, [itf], "interface"),
                                    (1, [bottom], "b_bottom")):
                gmsh.model.addPhysicalGroup(dim, tags, name=name)
            gmsh.model.mesh.generate(2)
            gmsh.write(str(path))

    on_rank_zero(COMM, build)
    return path


def _interface_facets(path: pathlib.Path) -> np.ndarray:
    """The lengths of the interface's facets in the .msh file, left to right."""
    import gmsh
    from breakwater.meshes import gmsh_session

    with gmsh_session():
        gmsh.open(str(path))
        tag = next(t for d, t in gmsh.model.getPhysicalGroups(1)
                   if gmsh.model.getPhysicalName(d, t) == "interface")
        x = gmsh.model.mesh.getNodesForPhysicalGroup(1, tag)[1].reshape(-1, 3)[:, 0]
    return np.diff(np.sort(x))


def test_graded_interface_compares_the_penetration_with_its_facet(
        shared_dir: pathlib.Path) -> None:
    """A graded interface (fine where the contact presses most, coarse elsewhere): the
    largest penetration is compared with the facet where it is largest, not the mean.

    A block whose top slopes (0.2 m high at its left, 0.6 m at its right) rests on
    another under gravity on a penalty ε_n far softer than the blocks (E/ε_n = 34 m for
    1 m blocks: they are rigid against it). A rigid block on a penalty's springs takes the
    linear pressure of its weight and moment, here p(x) = ρ g H(x) (each column carries
    its own weight), so the law p = ε_n g gives the largest penetration, at the right
    end, δ = ρ g H(0.5) / ε_n, within a few % (the blocks' own deformation, of order
    ε_n L / E = 3 %: 10 % allowed). ε_n is chosen for δ = 2 % of the finest facet (the
    right end's, 0.02 m): 5 times 1 % of h there, 0.4 times 1 % of the mean h = 0.1 m.
    Before, the report compared δ with the mean and said nothing of it (the warning of
    the settlement criterion alone); now it warns, naming h and the facet.
    """
    import json

    from blocks import two_block_case

    from breakwater import cli

    ratio = 1.3314  # 10 facets over 1 m, geometric, the last (the right end's) 0.02 m
    mesh = _graded_blocks(shared_dir / "graded.msh", ratio)
    sizes = COMM.bcast(_interface_facets(mesh) if COMM.rank == 0 else None)
    h_end, h_mean = float(sizes[-1]), float(sizes.mean())
    assert len(sizes) == 10 and h_end == pytest.approx(0.02, rel=0.01)
    assert h_mean == pytest.approx(0.1, rel=1e-12) and sizes.min() == h_end
    ρ, g, H = 2000.0, 9.81, 0.6
    penalty = ρ * g * H / (0.02 * h_end)  # δ = 2 % of h_end
    case = shared_dir / "graded.toml"
    if COMM.rank == 0:
        case.write_text(two_block_case(mesh.name, tail="[output]\nfield_interval = 0\n"
                                       "figures = false\n")
                        .replace("penalty = 1e12", f"penalty = {penalty!r}")
                        .replace("end_time = 1e-3", "end_time = 2e-4"))
    COMM.barrier()
    out = shared_dir / "out"
    assert cli.main(["run", str(case), "--out", str(out), "--no-progress", "--quiet"]) == 0
    q = json.loads((out / "summary.json").read_text())["contact_quality"]["interface"]
    δ = q["static_penetration"]
    assert δ == pytest.approx(ρ * g * H / penalty, rel=0.1)
    assert q["element_size"] == pytest.approx(h_mean, rel=1e-9)
    assert δ < 0.01 * h_mean  # the mean h hides it
    assert "static_penetration_over_h" in q["issues"], q["warnings"]
    warning = next(w for w in q["warnings"] if "static penetration" in w and "element" in w)
    assert (f"static penetration {δ:.3g} m > 1% of the element size h = {h_end:.3g} m, the "
            "facet where it is largest; ") in warning, warning
    assert q["penetration_element_size"] == pytest.approx(h_end, rel=1e-9)
    assert q["static_penetration_over_h"] == pytest.approx(δ / h_end, rel=1e-12)


def test_facet_size() -> None:
    # As the mean h: a segment's length; in 3D the side of the equilateral triangle or
    # the square of the facet's area (so a regular facet's size is its side).
    from breakwater.model.pairs import facet_size

    assert facet_size(np.array([[0.0, 1.0], [3.0, 5.0]])) == pytest.approx(5.0, rel=1e-15)
    s = 2.0
    triangle = np.array([[0, 0, 0], [s, 0, 0], [s / 2, s * np.sqrt(3) / 2, 0]])
    assert facet_size(triangle) == pytest.approx(s, rel=1e-14)
    square = np.array([[0, 0, 1], [3, 0, 1], [0, 3, 1], [3, 3, 1]], float)  # v₃ opp. v₀
    assert facet_size(square) == pytest.approx(3.0, rel=1e-15)
    assert facet_size(np.stack([triangle, 2 * triangle])) == pytest.approx([s, 2 * s])


def test_dynamic_penetration_against_the_smallest_facet() -> None:
    # Nothing penetrates in the static state: a dynamic penetration is compared with the
    # interface's smallest facet (the run cannot tell where it will press), and the
    # summary's ratios with it; without a measured size (an older checkpoint), the mean.
    args = {**_goda(), "static_penetration": 0.0}
    h = args["element_size"]
    q = quality.assess(**args, dynamic_penetration=0.005 * h, penetration_size=h / 4)
    assert q.issues == ("dynamic_penetration_over_h",)
    assert f"> 1% of the element size h = {h / 4:.3g} m, the smallest facet of the " \
           "interface; " in q.warnings[0]
    d = q.as_dict()
    assert d["penetration_element_size"] == h / 4 and d["element_size"] == h
    assert d["dynamic_penetration_over_h"] == pytest.approx(0.02, rel=1e-14)
    low, _ = q.suggested_penalty  # r = 2: ε_n (2 / 0.8)² (the edge's exponent ½)
    assert low == pytest.approx((2 / 0.8) ** 2 * args["penalty"], rel=1e-12)
    assert quality.assess(**args, dynamic_penetration=0.005 * h).issues == ()


def test_penetration_facet_does_not_depend_on_round_off() -> None:
    # The facet h_δ the static penetration is compared with: nodes whose penetrations
    # differ by round-off (1.7e-5 relative: goda3d's block base edge, uniform along z,
    # 2.40549e-5 or 2.40545e-5 m as its sides were free or on rollers) give the same h_δ,
    # the smallest of theirs, whichever is the deeper. Before, the deepest node's alone:
    # 0.0143 or 0.0447 m (0.17 % or 0.054 % of h).
    from breakwater.model.pairs import penetration_facet

    sizes = np.array([0.0447, 0.0143, 0.03, 0.01])
    for deep in (0, 1):
        gap = np.array([-2.40545e-5, -2.40545e-5, -1e-5, 1e-4])
        gap[deep] = -2.40549e-5
        assert penetration_facet(gap, sizes) == 0.0143
    # A node 10 % shallower is another penetration: not counted (its facet is smaller).
    assert penetration_facet(np.array([-1e-5, -0.9e-5]), np.array([0.04, 0.01])) == 0.04
    # No penetration: the smallest facet.
    assert penetration_facet(np.array([1e-6, 0.0]), np.array([0.04, 0.02])) == 0.02
