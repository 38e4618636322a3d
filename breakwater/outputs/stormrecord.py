"""A storm's per-wave record: ``waves.csv`` and the summary's ``storm`` block.

Written at the end of a run (finished, failed or interrupted: the waves finished by
then) from the history rows. A storm load of the case (``[loads.<name>.storm]``)
adds three pair probes on the contact pair under the caisson's base, at the base's two
ends (``<load>_base_lo`` at the smaller x, ``<load>_base_hi``) and at its middle
(``<load>_base_mid``), and its summary entry
(``loads.<name>.storm``) holds the waves and how to read the probes
(:func:`breakwater.casefile.stormbuild.storm_outputs`). Per wave k, over its interval
``start < t <= start + T`` (the state at its start: the last row at or before it):

- ``sliding``: the change over the wave of the caisson's horizontal displacement
  relative to the mound at the middle of its base (caisson minus mound,
  ``slave_ux − master_ux`` of the mid probe), positive landward (away from the loaded
  face): the residual slip the wave left (the elastic part returns when the force is
  off; what is still moving at the wave's end is counted in the next wave). Not the
  ends': under the wave's overturning moment and uplift the seaward end of the base
  unloads and slips on its own (partial slip) while the rest sticks, and ratchets
  landward wave after wave; on the prototype example its relative displacement grew
  by 0.76 mm over 10 waves that did not slide the caisson (the rigid block's 0, the
  rear end's 0 and the middle's 1e-9 m): a mean of the two ends counted half of it as
  sliding. The middle, under the highest contact pressure, slips only when the whole
  base does;
- ``cumulative_sliding``: the sum of ``sliding`` up to this wave;
- ``rocking``: the largest |θ − θ₀| in the wave, θ the slope of the caisson's vertical
  displacement between the base's ends ((u_y,hi − u_y,lo)/(x_hi − x_lo), rad,
  counter-clockwise positive), θ₀ that of the static state;
- ``max_contact_pressure``: ε_n × the pair's largest penetration in the wave (Pa;
  the penalty law's pressure at the most loaded node or integration point);
- ``peak_force_per_length``: the largest horizontal force of the front pressure at the
  step ends in the wave, p₁(t) × the wave's shape integrated over the loaded face (N/m;
  in 3D the whole face's over the caisson's length along z, the base's: per metre too);
- ``rigid_sliding``: the rigid-block model's sliding under the same wave load
  (:func:`rigid_record`; NaN where it does not apply).

:func:`rigid_record` is the rigid-block reference (Shimosako & Takahashi;
:mod:`breakwater.storms.rigid`) of the same storm on the FE model's caisson: its mass
and W' (the static normal force on the mound), μ of the pair, no added mass (the FE
model has no water), each wave from rest.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from breakwater.common.plotstyle import default_style
from breakwater.outputs.historyrows import column
from breakwater.outputs.sliding import SMALL_SLIDING

__all__ = ["COLUMNS", "SMALL_SLIDING", "read_waves", "rigid_record", "small_sliding_warning",
           "storm_figures", "storm_record",
           "write_storm_record", "write_waves"]

COLUMNS = ("wave", "height", "period", "start", "end", "peak_force_per_length", "sliding",
           "cumulative_sliding", "rocking", "max_contact_pressure", "rigid_sliding")
"""The columns of ``waves.csv``."""


def _sliding(rows: Sequence[Mapping[str, float]], r: Mapping[str, Any]) -> np.ndarray:
    """The caisson's horizontal displacement relative to the mound at mid-base, landward."""
    p = r["mid"]
    return (column(rows, f"{p}_slave_ux") - column(rows, f"{p}_master_ux")) \
        * r["sign"] * r["landward"]


def _rotation(rows: Sequence[Mapping[str, float]], r: Mapping[str, Any]) -> np.ndarray:
    """The slope of the caisson's u_y between the base's ends (rad)."""
    side = "slave" if r["sign"] > 0 else "master"
    return (column(rows, f"{r['hi']}_{side}_uy") - column(rows, f"{r['lo']}_{side}_uy")) \
        / r["length"]


def storm_record(rows: Sequence[Mapping[str, float]], storm: Mapping[str, Any],
                 p1: Callable[[float], float] | None = None,
                 rigid: Mapping[str, Any] | None = None
                 ) -> tuple[list[dict[str, float]], dict[str, Any]]:
    """The per-wave rows of the waves finished, and the summary's ``storm`` block.

    Args:
        rows: The history rows (the static state's first).
        storm: The load's ``storm`` summary entry (waves and ``record``: the probes'
            names, the landward sign, the caisson's side of the pair, the base length,
            the pair's penetration column and penalty).
        p1: t ↦ p₁ of the storm (the model's amplitude of the front); None: no peak
            force.
        rigid: The rigid-block reference (:func:`rigid_record`), put beside each wave
            and in the block; None: none.
    """
    r = storm["record"]
    waves = storm["waves"]
    out: list[dict[str, float]] = []
    if not rows:
        return out, _block(out, waves, r)
    times = column(rows, "t")  # increasing
    length = r.get("breakwater_length", 1.0)  # 3D: the force per metre of the caisson
    slide, rotation = _sliding(rows, r), _rotation(rows, r)
    penetration = column(rows, r["penetration"], math.nan)
    total = 0.0
    for k, w in enumerate(waves):
        start, end = w["start"], w["start"] + w["period"]
        if times[-1] < end * (1 - 1e-12):
            break  # not finished
        i0 = int(np.searchsorted(times, start, side="right")) - 1  # the last t <= start
        # The rows of start < t <= end (none: the row before).
        inside = slice(i0 + 1, max(int(np.searchsorted(times, end * (1 + 1e-12),
                                                       side="right")), i0 + 1))
        if inside.start == inside.stop:
            inside = slice(i0, i0 + 1)
        i1 = inside.stop - 1
        sliding = float(slide[i1] - slide[i0])
        total += sliding
        rocking = float(np.abs(rotation[inside] - rotation[0]).max())
        pressure = r["penalty"] * float(penetration[inside].max())
        force = math.nan if p1 is None else max(
            p1(float(t)) * w["front_force_per_p1"] for t in times[inside]) / length
        out.append({"wave": k + 1, "height": w["height"], "period": w["period"],
                    "start": start, "end": end, "peak_force_per_length": force,
                    "sliding": sliding, "cumulative_sliding": total, "rocking": rocking,
                    "max_contact_pressure": pressure,
                    "rigid_sliding": (rigid or {}).get("sliding", [math.nan] * (k + 1))[k]})
    block = _block(out, waves, r)
    if rigid is not None:
        block["rigid"] = dict(rigid)
    return out, block


def rigid_record(loads: Sequence[Any], *, mass: float, weight: float, base_width: float,
                 toe_depth: float, friction: float, density: float, gravity: float
                 ) -> dict[str, Any]:
    """The rigid-block model's sliding under each wave's load (each from rest).

    Args:
        loads: The waves' loads (:class:`~breakwater.storms.waves.WaveLoad`), the FE run's.
        mass: The caisson's mass per metre (kg/m).
        weight: W' (N/m): the FE model's static normal force on the mound.
        base_width: B (m).
        toe_depth: h' (m).
        friction: μ.
        density: Water density (kg/m³; no added mass: not used but checked).
        gravity: g (m/s²).

    Returns:
        ``sliding`` per wave, ``total_sliding``, the inputs, and ``note`` when a wave's
        slide lasts into the next wave (the from-rest model does not hold there); or
        ``error`` when the model cannot apply (μ = 0: no resistance).
    """
    from breakwater.storms.rigid import Caisson, slide_motion

    inputs = {"mass": mass, "weight": weight, "friction": friction, "added_mass": False,
              "model": "breakwater.storms.rigid: (M) x'' = P - mu (W' - U), from rest per wave"}
    try:
        caisson = Caisson(mass, base_width, toe_depth, friction, added_mass=False,
                          density=density, gravity=gravity, weight=weight)
        motions = [slide_motion(load, caisson) for load in loads]
    except ValueError as e:
        return {**inputs, "error": str(e)}
    sliding = [m.distance for m in motions]
    out: dict[str, Any] = {**inputs, "sliding": sliding, "total_sliding": sum(sliding)}
    late = [k + 1 for k, (m, load) in enumerate(zip(motions, loads, strict=True))
            if m.stop is not None and k + 1 < len(loads)
            and load.wave.start + m.stop > loads[k + 1].wave.start]
    if late:
        out["note"] = (f"waves {late}: the rigid block still slides when the next wave "
                       "begins (the from-rest model does not hold there)")
    return out


def _block(out: list[dict[str, float]], waves: Sequence[Mapping[str, Any]],
           r: Mapping[str, Any]) -> dict[str, Any]:
    """The summary's ``storm`` block."""
    block: dict[str, Any] = {"waves": len(waves), "waves_finished": len(out),
                             "record": "waves.csv",
                             "total_sliding": out[-1]["cumulative_sliding"] if out else 0.0,
                             "sliding_measure": "horizontal displacement of the caisson "
                             "relative to the mound at mid-base, landward (pair probe "
                             f"{r['mid']})"}
    if out:
        big = max(out, key=lambda w: w["height"])
        block["largest_wave"] = {"wave": int(big["wave"]), "height": big["height"],
                                 "period": big["period"], "sliding": big["sliding"]}
        most = max(out, key=lambda w: w["sliding"])
        block["most_sliding"] = {"wave": int(most["wave"]), "height": most["height"],
                                 "sliding": most["sliding"]}
    return block


def write_waves(path: Any, waves: Sequence[Mapping[str, float]]) -> Any:
    """Write ``waves.csv`` (atomically): a header, one row per finished wave."""
    from breakwater.common import files

    lines = [",".join(COLUMNS)]
    for w in waves:
        lines.append(",".join(str(int(w[c])) if c == "wave" else repr(float(w[c]))
                              for c in COLUMNS))
    return files.atomic_write_text(path, "\n".join(lines) + "\n")


def read_waves(path: Any) -> dict[str, Any]:
    """``waves.csv`` as one NumPy array per column (none when it holds no wave)."""
    lines = [line for line in open(path, encoding="utf-8").read().splitlines() if line]
    names = lines[0].split(",")
    values = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    return {n: values[:, k] if len(values) else np.zeros(0) for k, n in enumerate(names)}


@default_style
def storm_figures(directory: Any, folder: Any) -> list[Any]:
    """The storm's figures from ``waves.csv`` (none without it or a finished wave).

    ``storm_sliding.png``: the cumulative sliding against the waves' end times (and
    numbers); ``storm_sliding_per_wave.png``: each wave's sliding against H.
    """
    import pathlib

    from matplotlib.figure import Figure

    from breakwater.common.files import WAVES

    path = pathlib.Path(directory) / WAVES
    if not path.is_file():
        return []
    w = read_waves(path)
    if not len(w.get("wave", ())):
        return []
    out = []
    fig = Figure(figsize=(7, 4))
    ax = fig.add_subplot()
    ax.step([0.0, *w["end"]], [0.0, *(1e3 * w["cumulative_sliding"])], where="post")
    ax.plot(w["end"], 1e3 * w["cumulative_sliding"], "o")
    ax.set_xlabel("t (s): the end of each wave")
    ax.set_ylabel("cumulative sliding (mm)")
    top = ax.secondary_xaxis("top")
    top.set_xticks(w["end"], [str(int(k)) for k in w["wave"]])
    top.set_xlabel("wave")
    ax.grid(alpha=0.3)
    out.append(_save(fig, pathlib.Path(folder) / "storm_sliding.png"))
    fig = Figure(figsize=(6, 4))
    ax = fig.add_subplot()
    ax.plot(w["height"], 1e3 * w["sliding"], "o", label="finite elements")
    if "rigid_sliding" in w and np.isfinite(w["rigid_sliding"]).any():
        ax.plot(w["height"], 1e3 * w["rigid_sliding"], "x", label="rigid block")
        ax.legend()
    ax.set_xlabel("H (m)")
    ax.set_ylabel("sliding of the wave (mm)")
    ax.grid(alpha=0.3)
    out.append(_save(fig, pathlib.Path(folder) / "storm_sliding_per_wave.png"))
    return out


def _save(fig: Any, path: Any) -> Any:
    """Save a figure atomically (:func:`breakwater.outputs.figures` does the same)."""
    from breakwater.common.files import temporary_path, writing

    tmp = temporary_path(path)
    with writing(path):
        fig.savefig(tmp, dpi=150, bbox_inches="tight")
        tmp.replace(path)
    return path


def small_sliding_warning(rows: Sequence[Mapping[str, float]], r: Mapping[str, Any],
                          h: float | None) -> str | None:
    """A warning when a conforming pair's base slipped beyond :data:`SMALL_SLIDING` h.

    A conforming (node-to-node) pair holds each slave node to its master node: valid
    while the slip is small against the element size. A storm that slides the caisson
    further needs a general pair (bodies meshed apart, finite sliding).
    """
    if not r.get("conforming") or not h or not rows:
        return None
    names = [r[k] for k in ("lo", "mid", "hi") if k in r]
    slip = max((float(np.abs(s - s[0]).max())
                for s in (column(rows, f"{p}_slip", 0.0) for p in names)), default=0.0)
    if slip <= SMALL_SLIDING * h:
        return None
    return (f"the caisson's base slipped up to {slip:.3g} m on the conforming pair "
            f"'{r.get('pair')}', {100 * slip / h:.3g}% of its element size h = {h:.3g} m: "
            "node-to-node contact holds only for slips small against h (the results "
            "past that are not reliable); mesh the bodies apart with a general pair "
            "(finite sliding: a [contact.<pair>] with slave_surface and master_surface; the "
            "manual's general contact page)")


def write_storm_record(model: Any, rows: Sequence[Mapping[str, float]],
                       summary: dict[str, Any], directory: Any) -> None:
    """A storm's ``waves.csv`` (rank 0) and the summary's ``storm`` block (collective).

    Every rank computes the same record from the same rows; the rigid-block reference
    (:func:`rigid_record`) takes the storm's wave loads from the model's front load (its
    amplitude, a :class:`~breakwater.storms.stormload.WaveHistory`), M and W' from the
    static state when its pair's slave is the caisson (W' the static normal force: the
    weight and any load at t = 0), else M from the caisson's weight and W' = M g; in 3D
    both per metre of the caisson's length along z (the record's ``breakwater_length``),
    as Goda's loads of the waves are.

    Args:
        model: The contact model (:class:`~breakwater.model.model.ContactModel`).
        rows: The history rows.
        summary: The run's summary (``loads.<name>.storm`` read, ``storm`` set).
        directory: The output folder.
    """
    import pathlib

    from breakwater.common.files import WAVES
    from breakwater.common.parallel import on_rank_zero

    for name, info in summary.get("loads", {}).items():
        if "storm" not in info:
            continue
        p1 = next((ld.spec.amplitude for ld in model.loads
                   if ld.spec.name == name and ld.parameters is not None), None)
        loads = getattr(p1, "loads", None)
        r = info["storm"]["record"]
        g = float(np.linalg.norm(model.gravity.value))
        rigid: dict[str, Any] | None = None
        if loads is not None and not g > 0:
            rigid = {"error": "the model has no gravity: the rigid block has no weight"}
        elif loads is not None:
            weights = model.weight()  # collective: every rank
            static = summary.get("static") or {}
            if static.get("slave") == r["caisson"] and static.get("contact_resultant"):
                mass, weight = static["weight"] / g, static["contact_resultant"]
            else:
                mass = weights[model.body(r["caisson"]).index] / g
                weight = mass * g
            # 3D: per metre of the caisson's length along z, as the waves' loads are.
            length = r.get("breakwater_length", 1.0)
            mass, weight = mass / length, weight / length
            rigid = rigid_record(loads, mass=mass, weight=weight, base_width=r["length"],
                                 toe_depth=r["toe_depth"], friction=r["friction"],
                                 density=r["density"], gravity=g)
        waves, block = storm_record(rows, info["storm"], p1, rigid)
        quality = (summary.get("contact_quality") or {}).get(r.get("pair"), {})
        warning = small_sliding_warning(rows, r, quality.get("element_size"))
        if warning is not None:
            block["warning"] = warning
        on_rank_zero(model.comm, lambda waves=waves: bool(  # type: ignore[misc]
            write_waves(pathlib.Path(directory) / WAVES, waves)))
        summary["storm"] = {"load": name, **block}
