"""The whole case as typed settings: its tables together, checked against each other.

:class:`CaseSettings` holds every table of a case file (:mod:`breakwater.casefile.tables`,
:mod:`breakwater.casefile.loads`), checks what no table can check alone (the bodies a
pair, a probe, a load or the calibration names; the names of the output files; a
general pair's solver; the initial loads; the time a load acts), and gives the values
derived from them (the output folder, the resolved TOML data, the case with a
calibrated modulus written in). It is the data of :class:`breakwater.casefile.case.Case`,
which adds the building of a run (:mod:`breakwater.casefile.build`); what builds a run
takes a :class:`CaseSettings`. Nothing here needs the solver stack.
"""

from __future__ import annotations

import math
import pathlib
from dataclasses import dataclass, replace
from typing import Any, Self

from breakwater.casefile.dimension import dimension_problem
from breakwater.casefile.loads import LoadCase
from breakwater.casefile.tables import (
    BodyCase,
    CalibrationCase,
    ContactCase,
    DampingCase,
    FixedCase,
    InitialCase,
    MeshCase,
    OutputCase,
    TimeCase,
)
from breakwater.common.files import name_problem
from breakwater.config.fields import InvalidField, positive, setting, suggest, to_toml
from breakwater.config.typecheck import check_fields

__all__ = ["CaseSettings"]


_DEFAULT_MESH = MeshCase()
_NO_DAMPING = DampingCase()
_NO_CALIBRATION = CalibrationCase()
_DEFAULT_OUTPUT = OutputCase()
_DEFAULT_INITIAL = InitialCase()


@dataclass(frozen=True, kw_only=True)
class CaseSettings:
    """A whole case's settings (see :mod:`breakwater.casefile.case` and its reference).

    Read by :func:`~breakwater.casefile.case.load_case` as a
    :class:`~breakwater.casefile.case.Case`; every key is listed by
    :func:`~breakwater.casefile.case.case_reference`.
    """

    name: str = setting("case", doc="case name (default: the file name); default output "
                        "folder results/<name>, so a folder name of its own: not . or .., "
                        "no / \\ : or control characters, at most 255 bytes")
    description: str = setting("", doc="free text")
    out_of_plane_length: float = setting(1.0, unit="m", doc="length of the real structure "
                                         "out of plane: impulses, forces and target "
                                         "stiffnesses of the real structure are divided "
                                         "by it")
    gravity: tuple[float, ...] = setting((0.0, -9.81), unit="m/s²", doc="acceleration of "
                                         "gravity")
    mesh: MeshCase = setting(_DEFAULT_MESH, doc="the mesh")  # noqa: RUF009 (a field() with docs)
    bodies: tuple[BodyCase, ...] = setting((), doc="the bodies")
    contact: tuple[ContactCase, ...] = setting((), doc="contact pairs")
    fixed: tuple[FixedCase, ...] = setting((), doc="fixed boundaries")
    loads: tuple[LoadCase, ...] = setting((), doc="surface loads (see breakwater.casefile.loads)")
    initial: InitialCase = setting(_DEFAULT_INITIAL, doc="the initial state")  # noqa: RUF009 (a field() with docs)
    damping: DampingCase = setting(_NO_DAMPING, doc="Rayleigh damping")  # noqa: RUF009 (a field() with docs)
    calibration: CalibrationCase = setting(_NO_CALIBRATION, doc="stiffness calibration")  # noqa: RUF009 (a field() with docs)
    time: TimeCase = setting(doc="time integration")  # noqa: RUF009 (a field() with docs)
    output: OutputCase = setting(_DEFAULT_OUTPUT, doc="outputs")  # noqa: RUF009 (a field() with docs)

    def __post_init__(self) -> None:
        check_fields(self)
        self._check()

    # --- validation ----------------------------------------------------------------

    def _check(self) -> None:
        problem = name_problem(self.name)
        if problem is not None:  # the name is the default output folder results/<name>
            raise InvalidField("name", problem)
        positive(self.out_of_plane_length, "out_of_plane_length")
        if len(self.gravity) not in (2, 3):
            raise InvalidField("gravity", f"must have 2 components (plane strain) or 3 (3D) "
                               f"(got {list(self.gravity)})")
        shown = ", ".join(f"{c:g}" for c in self.gravity)
        if not math.isfinite(sum(c * c for c in self.gravity)):  # |g|² of the energy
            raise InvalidField("gravity", f"[{shown}] m/s²: |g|² overflows")
        for b in self.bodies:  # the body force ρ g of the run
            if not math.isfinite(b.density * max(map(abs, self.gravity))):
                raise InvalidField(f"bodies.{b.name}.density", f"{b.density:g} kg/m³ times "
                                   f"gravity [{shown}] m/s² overflows")
        dimension_problem(self)
        if not self.bodies:
            raise InvalidField("bodies", "the case needs at least one body ([bodies.<name>])")
        self._check_names_once()
        names = [b.name for b in self.bodies]
        # The ParaView files fields_<body>.bp and contact_<pair>.bp are named after them.
        for where, file in [*((f"bodies.{b.name}", f"fields_{b.name}.bp") for b in self.bodies),
                            *((f"contact.{c.name}", f"contact_{c.name}.bp")
                              for c in self.contact)]:
            problem = name_problem(file)
            if problem is not None:
                raise InvalidField(where, f"the name cannot name the output file {file[:40]}"
                                   f"{'...' if len(file) > 40 else ''}: it {problem}")

        def body(value: str, where: str) -> None:
            if value not in names:
                raise InvalidField(where, f"no body named '{value}'{suggest(value, names)} "
                                   f"(bodies: {', '.join(names)})")

        for c in self.contact:
            body(c.slave, f"contact.{c.name}.slave")
            body(c.master, f"contact.{c.name}.master")
            if c.general and self.time.solver == "reference":
                raise InvalidField("time.solver", f"contact.{c.name} is a general pair "
                                   '(slave_surface/master_surface): it needs "fast" (or '
                                   '"auto")')
        cal = self.calibration
        if cal.enabled and any(c.general for c in self.contact):
            raise InvalidField("calibration.enabled", "the calibration bonds conforming "
                               "pairs only; a case with general pairs cannot calibrate")
        if cal.enabled:
            body(cal.body, "calibration.body")
            body(cal.structure, "calibration.structure")
            if cal.body == cal.structure:
                raise InvalidField("calibration.structure", "must differ from calibration.body")
            if cal.stiffness is None:
                raise InvalidField("calibration.stiffness", "missing (the target stiffness, N/m)")
        for b in self.bodies:
            calibrated = cal.enabled and b.name == cal.body
            if calibrated and b.has_modulus:
                raise InvalidField(f"bodies.{b.name}.shear_modulus",
                                   "the calibrated body must not give a modulus (remove it or "
                                   "set calibration.enabled = false)")
            if not calibrated and not b.has_modulus:
                raise InvalidField(f"bodies.{b.name}.shear_modulus",
                                   "missing: give shear_modulus or young_modulus (or calibrate "
                                   "it with [calibration])")
        for p in self.output.probes:
            body(p.body, f"output.probes.{p.name}.body")
        for ld in self.loads:
            if ld.body is not None:
                body(ld.body, f"loads.{ld.name}.body")
            if ld.kind == "pulse" and not math.isfinite(ld.total_impulse
                                                        / self.out_of_plane_length):
                raise InvalidField("out_of_plane_length", f"the impulse of loads.{ld.name} "
                                   f"per metre, {ld.total_impulse:g} N s / "
                                   f"{self.out_of_plane_length:g} m, overflows")
            ld.check_time(self.time.end_time, self.time.smallest_dt)
        loads = [ld.name for ld in self.loads]
        for name in self.initial.loads or ():
            if name not in loads:
                raise InvalidField("initial.loads", f"no load named '{name}'"
                                   f"{suggest(name, loads)} (loads: {', '.join(loads) or 'none'})")
        pairs = [c.name for c in self.contact]
        for q in self.output.pair_probes:
            if q.pair not in pairs:
                raise InvalidField(f"output.pair_probes.{q.name}.pair",
                                   f"no contact pair '{q.pair}'{suggest(q.pair, pairs)} "
                                   f"(pairs: {', '.join(pairs) or 'none'})")

    def _check_names_once(self) -> None:
        """Refuse an entry of a named collection given twice (the case from Python).

        A case file's entries are its tables' keys, given once; ``dataclasses.replace``
        can add one of the same name: ``contact=(*case.contact, replace(c, friction=0.3))``
        ran with both pairs, the contact's stiffness and friction doubled, a load given
        twice applied twice its impulse, and the summary kept one of each name.
        """
        for where, entries in (("bodies", self.bodies), ("contact", self.contact),
                               ("fixed", self.fixed), ("loads", self.loads),
                               ("output.probes", self.output.probes),
                               ("output.pair_probes", self.output.pair_probes)):
            seen: set[str] = set()
            for entry in entries:
                if entry.name in seen:
                    raise InvalidField(f"{where}.{entry.name}", f"given twice (each entry of "
                                       f"{where} once, as the case file's [{where}.<name>] "
                                       "tables: replace it, e.g. tuple(dataclasses.replace(x, "
                                       f"...) if x.name == '{entry.name}' else x for x in "
                                       f"case.{where}))")
                seen.add(entry.name)

    # --- derived values ------------------------------------------------------------

    @property
    def output_directory(self) -> pathlib.Path:
        """The output folder (``results/<name>`` unless set)."""
        return pathlib.Path(self.output.directory or f"results/{self.name}")

    def body(self, name: str) -> BodyCase:
        """The body of that name."""
        for b in self.bodies:
            if b.name == name:
                return b
        raise KeyError(name)

    def resolved(self) -> dict[str, Any]:
        """The fully resolved case as TOML-ready data (defaults filled).

        ``load_case`` of a file holding this gives back the same resolved data. The case
        a run used (:attr:`BuiltCase.case <breakwater.casefile.build.BuiltCase.case>`) has
        the calibrated modulus written into the body and ``calibration.enabled`` false:
        its resolved data reproduce the run without calibrating again.
        """
        data = to_toml(self)
        if not self.mesh.generated:
            del data["mesh"]["goda"]
            del data["mesh"]["refinement"]
            del data["mesh"]["max_elements"]
        data["output"]["directory"] = str(self.output_directory)
        return data

    def calibrated(self, body: str, shear_modulus: float) -> Self:
        """A new case: the body's shear modulus given (Pa), the calibration off."""
        bodies = tuple(replace(b, shear_modulus=shear_modulus) if b.name == body else b
                       for b in self.bodies)
        return replace(self, bodies=bodies,
                       calibration=replace(self.calibration, enabled=False))
