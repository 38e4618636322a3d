"""Expected sliding of a prototype caisson over a design storm (rigid-block model, no FE).

A prototype in the range of Shimosako & Takahashi's (1999) and Goda & Takagi's (2000)
examples (we could not obtain their worked example's exact numbers, so this does not
reproduce a published value): a caisson of B = 30 m standing in h = 20 m of water on a
mound (h' = 14.5 m, berm at d = 11 m, crest h_c = 5 m), bulk density 2.1 t/m³ (concrete
and sand fill), μ = 0.6, under a storm of H_1/3 = 8 m, T_1/3 = 14 s and 1000 waves (about
3.9 h). Its conventional safety factor against sliding under Goda's H_max = 1.8 H_1/3 is
1.24 (the usual design criterion is 1.2).

Usage: ``python examples/storm_rigid.py [STORMS] [OUTDIR]`` (default 200 storms, the
CSV and the figure in ``results/storm_rigid/``); about 2 s of CPU per 100 storms. A bad
argument (``abc``, ``0``, a third one, an OUTDIR that cannot be made) is refused in one
line, exit status 2.
"""

from __future__ import annotations

import pathlib
import sys

from breakwater.loads.wavepressure import goda_pressure
from breakwater.storms.montecarlo import expected_sliding, plot, write_csv
from breakwater.storms.rigid import Caisson
from breakwater.storms.seastate import SeaState
from breakwater.storms.waves import Site

B, H, H1, D, HC = 30.0, 20.0, 14.5, 11.0, 5.0
SITE = Site(depth=H, toe_depth=H1, berm_depth=D, crest_height=HC, base_width=B)
CAISSON = Caisson(mass=2100.0 * B * (H1 + HC), base_width=B, toe_depth=H1, friction=0.6)
SEA = SeaState(significant_height=8.0, significant_period=14.0, waves=1000)


USAGE = "usage: python examples/storm_rigid.py [STORMS] [OUTDIR]"


def arguments(argv: list[str]) -> tuple[int, pathlib.Path]:
    """The number of storms and the output folder (made) from the command line.

    Raises:
        ValueError: Not a whole number >= 1 of storms, more than two arguments, or a
            folder that cannot be made (one line; a traceback before).
    """
    if len(argv) > 2:
        raise ValueError(f"expected at most 2 arguments, got {len(argv)}")
    storms = argv[0] if argv else "200"
    if not storms.isdecimal() or int(storms) < 1:
        raise ValueError(f"STORMS: expected a whole number >= 1, got '{storms}'")
    out = pathlib.Path(argv[1] if len(argv) > 1 else "results/storm_rigid")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise ValueError(f"OUTDIR: cannot make '{out}' ({e.strerror})") from None
    return int(storms), out


def main(argv: list[str]) -> None:
    """Run the Monte Carlo and print the result (exit 2 on a bad argument)."""
    try:
        storms, out = arguments(argv)
    except ValueError as e:
        print(f"storm_rigid.py: {e} ({USAGE})", file=sys.stderr)
        raise SystemExit(2) from None
    design = goda_pressure(1.8 * SEA.significant_height, SEA.significant_period, H, H1, D,
                           HC)
    safety = CAISSON.friction * (CAISSON.submerged_weight - design.uplift_force(B)) \
        / design.force
    result = expected_sliding(SEA, SITE, CAISSON, storms=storms, limits=(0.1, 0.3))
    p = result.percentiles
    print(f"caisson B = {B:g} m, W' = {CAISSON.submerged_weight / 1e3:.0f} kN/m, "
          f"safety factor against sliding under H_max = 1.8 H_1/3: {safety:.2f}")
    print(f"{storms} storms of {SEA.count} waves, H_1/3 = {SEA.significant_height:g} m, "
          f"T_1/3 = {SEA.significant_period:g} s")
    print(f"expected sliding per storm {result.mean:.3f} m ± {result.half_width():.3f} m "
          f"(95 % confidence; std {result.std:.3f} m); "
          f"percentiles 5/50/95: {p[5.0]:.3f} / {p[50.0]:.3f} / {p[95.0]:.3f} m")
    for lim, prob in result.exceedance.items():
        print(f"P(sliding > {lim:g} m) = {prob:.3f}")
    print(f"storms for the mean within 10 % at 95 % confidence: {result.storms_needed()}")
    print(write_csv(result, out / "storm_rigid.csv"))
    print(plot(result, out / "storm_rigid.png", title="storm_rigid: total sliding per storm"))


if __name__ == "__main__":
    main(sys.argv[1:])
