"""Command line: ``python -m breakwater {run,mesh,calibrate,sweep,show-case} [CASE] ...``.

``CASE`` is a case file (TOML), or the name of a built-in case (``goda``, the
default); ``sweep`` takes a study file instead (:mod:`breakwater.studies.studyfile`). Every
command takes ``--set key=value`` overrides (repeatable). Errors
the user can act on are one line on stderr, without a traceback unless ``--debug``:
exit status 2 for input errors (case, mesh, usage, no checkpoint to resume, an output
folder that cannot be written or that holds an input the outputs would replace: checked
before anything runs), 1 for a failed or interrupted (SIGTERM, SIGINT) run, a run whose
outputs could not be written (``cannot write <path>: <reason>``) included. ``run
--resume`` continues a killed run in the same output folder from its last checkpoint
(``output.checkpoint_interval``); ``sweep`` exits 0 only when every case of the study
finished.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import logging
import pathlib
import sys
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import replace
from typing import TYPE_CHECKING, NoReturn

from breakwater import __version__
from breakwater.common import files, folderlock, liveness
from breakwater.common.errors import BreakwaterError, CaseError, MeshError
from breakwater.common.parallel import on_rank_zero, shared_tempdir
from breakwater.common.xdmfinfo import is_xdmf
from breakwater.studies.studyfile import MAX_POINTS

if TYPE_CHECKING:
    from mpi4py import MPI

    from breakwater.casefile.case import Case

EXIT_OK, EXIT_FAILED, EXIT_INPUT = 0, 1, 2
PROG = "python -m breakwater"


def _rank() -> int:
    from mpi4py import MPI

    return MPI.COMM_WORLD.rank


class _Parser(argparse.ArgumentParser):
    """The command line's parser (and its subcommands'): a usage error is one line."""

    def error(self, message: str) -> NoReturn:
        """Exit with status 2 and one line: the error and where the options are listed."""
        self.exit(EXIT_INPUT, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _parse(parser: argparse.ArgumentParser, argv: Sequence[str] | None
           ) -> argparse.Namespace:
    """The parsed arguments, the parser's output printed by rank 0 only.

    Under mpiexec every rank parses the command line: what the parser prints (a usage
    error, ``--help``, ``--version``) was printed once per rank.
    """
    if _rank() == 0:
        return parser.parse_args(argv)
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        return parser.parse_args(argv)


def _say(text: str, quiet: bool = False) -> None:
    """Print on rank 0 only (unless quiet)."""
    if not quiet and _rank() == 0:
        print(text, flush=True)


@contextmanager
def _logging(args: argparse.Namespace) -> Iterator[None]:
    """Log to stderr on rank 0: warnings with --quiet, debug with --verbose.

    The ``breakwater`` logger is restored on exit (main() may be called in-process).
    """
    level = logging.WARNING if args.quiet else logging.DEBUG if args.verbose else logging.INFO
    logger = logging.getLogger("breakwater")
    saved = (logger.level, logger.propagate)
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("%(message)s"))
    logger.setLevel(level if _rank() == 0 else logging.CRITICAL)
    logger.addHandler(handler)
    logger.propagate = False
    try:
        yield
    finally:
        logger.removeHandler(handler)
        logger.setLevel(saved[0])
        logger.propagate = saved[1]


def _overrides(args: argparse.Namespace) -> list[str]:
    out = list(args.set or [])
    if getattr(args, "command", None) == "run" and args.out is not None:
        out.append(f"output.directory={json.dumps(str(args.out))}")
    return out


def _load(args: argparse.Namespace, static: bool = False) -> Case:
    from breakwater.casefile.case import load_case

    return load_case(args.case, _overrides(args), static=static)


def _inputs(args: argparse.Namespace, case: Case) -> list[pathlib.Path]:
    from breakwater.casefile.case import case_inputs

    return case_inputs(args.case, case)


def _check_output(folder: pathlib.Path, where: str, inputs: Sequence[pathlib.Path],
                  comm: MPI.Comm, patterns: Sequence[str] = files.OUTPUT_PATTERNS,
                  outputs: str = "the outputs", study: bool = False) -> None:
    """Refuse an output folder that cannot be written, or would replace an input.

    Or that holds the other kind's outputs (a study's for a run, a run's for a study).
    Before anything runs; rank 0 checks, every rank raises.

    Args:
        folder: The output folder.
        where: How the messages name it (``--out``, ``output.directory``).
        inputs: The files the command reads.
        comm: The ranks that raise.
        patterns: The names written in ``folder`` (a run's, or a study's).
        outputs: How the messages name what is written.
        study: Whether a study writes in ``folder`` (else a run).

    Raises:
        CaseError: ``cannot write <path>: <reason>``, a file of that name, an input
            (the case file, the mesh, a table, the study file) under an output's name,
            or a folder of the other kind (:func:`files.check_unmixed`).
    """
    def check() -> None:
        files.check_writable(folder, where)
        files.check_unmixed(folder, where, study)
        risky = files.overwritten_inputs(folder, inputs, patterns)
        if risky:
            raise CaseError(f"{where} {folder}: {outputs} would write over the input "
                            f"{risky[0]} (choose another output folder)")

    on_rank_zero(comm, check)


def _resumable(folder: pathlib.Path) -> bool:
    """``--auto-resume``: whether the folder holds a run to resume (rank 0).

    A run killed in it (by a batch scheduler's time limit, a lost node) is resumed, as
    with ``--resume`` (which refuses a checkpoint of another case, naming the keys that
    differ); a folder with no checkpoint or a finished run starts afresh, as ``run``
    without ``--resume``.
    """
    from breakwater.outputs import checkpoint

    summary = files.read_json(folder / files.SUMMARY) or {}
    if summary.get("status") == "finished" or not (folder / files.CHECKPOINT).is_file():
        return False
    checkpoint.check(folder)  # a damaged one: refused in one line, as --resume (kept)
    return True


# --- commands ---------------------------------------------------------------------

def _cmd_run(args: argparse.Namespace) -> int:
    from mpi4py import MPI

    from breakwater.common.console import StopSignal
    from breakwater.common.gmshtools import settle_signal_handlers
    from breakwater.outputs import checkpoint
    from breakwater.run import simulation

    comm = MPI.COMM_WORLD
    case = _load(args)
    folder = case.output_directory
    where = "--out" if args.out is not None else "output.directory"
    _check_output(folder, where, _inputs(args, case), comm)
    on_rank_zero(comm, lambda: liveness.check_not_running(folder, where))
    if args.auto_resume:
        args.resume = bool(on_rank_zero(comm, lambda: _resumable(folder)))
    if args.resume:
        # Fail early, before meshing and calibrating, when there is nothing to resume;
        # build_to_resume then refuses, as early, a checkpoint of another case.
        on_rank_zero(comm, lambda: checkpoint.check(folder))
    _say(f"breakwater {__version__}: case '{case.name}' -> {folder}"
         + (" (resuming)" if args.resume else ""), args.quiet)
    if comm.size > 1:  # ranks that wait for each other on shared cores crawl
        from breakwater.common.cores import core_warning, host_usage

        warning = core_warning(host_usage(comm), comm.size)
        if warning is not None:
            logging.getLogger("breakwater").warning("%s", warning)
    # SIGTERM or SIGINT while the case is meshed and calibrated: caught (it killed the
    # process, exit 143, leaving a half-made folder); the run then stops after its
    # static state, with a checkpoint, as at any step (the run's StopSignal nests).
    settle_signal_handlers()
    # Held from before the case is built (its summary, which names the run, is written
    # after): a second run started meanwhile is refused, not run into the same files.
    with folderlock.holding(folder, comm, where), StopSignal():
        if args.resume:  # the killed run's calibrated modulus (the same model, any ranks)
            from breakwater.run.resumecase import build_to_resume

            built = build_to_resume(case, comm)
        else:
            built = case.build(comm)
        if "calibration" in built.extra:
            c = built.extra["calibration"]
            per = " per m" if len(case.gravity) == 2 else ""  # plane strain: per metre
            _say(f"  calibrated {c['body']} shear modulus G = {c['shear_modulus']:.6g} Pa "
                 f"(K_x = {c['stiffness']:.6g} N/m{per}, error {c['relative_error']:.1e})",
                 args.quiet)
        output = replace(built.output, progress=args.progress)
        simulation.run(built.model, built.time, output, resolved_case=built.case.resolved(),
                       extra_summary=built.extra, report=not args.quiet, resume=args.resume)
    return EXIT_OK


def _cmd_mesh(args: argparse.Namespace) -> int:
    import meshio
    from mpi4py import MPI

    from breakwater import meshes  # type: ignore[attr-defined]  # breakwater.meshes maps to meshes/

    comm = MPI.COMM_WORLD
    out = pathlib.Path(args.out)
    if not meshio.extension_to_filetypes.get(out.suffix.lower()):
        raise CaseError(f"--out {out}: unknown mesh file suffix '{out.suffix}' "
                        "(use .msh, .xdmf, .vtu or another meshio format)")
    case = _load(args)
    xdmf = is_xdmf(out)
    if not xdmf and not case.mesh.generated and is_xdmf(pathlib.Path(case.mesh.source)):
        raise CaseError(f"--out {out}: the case's mesh is an XDMF ({case.mesh.source}); "
                        "breakwater converts gmsh meshes: give the .msh or .geo as "
                        "mesh.source, or --out x.xdmf")

    def check() -> None:
        if out.is_dir():
            raise CaseError(f"--out {out}: a folder (give a file name)")
        files.check_writable(out.parent, "--out")

    on_rank_zero(comm, check)
    with shared_tempdir(comm, "breakwater-mesh-") as folder:
        if xdmf:  # read as a run reads it (every check), written with its groups' names
            from breakwater.model.xdmfmesh import write_xdmf

            data = case.read_mesh(comm, folder)
            with files.writing(out):
                h5 = write_xdmf(data, out)
            _say(f"wrote {out} and {h5.name} (keep them together): a case reads it as "
                 f"mesh.source = \"{out.name}\", on any number of ranks; ParaView opens "
                 "it", args.quiet)
            return EXIT_OK
        source = case.mesh_file(comm, folder)
        with files.writing(out):
            meshes.convert(source, out, comm=comm)
    _say(f"wrote {out}", args.quiet)
    return EXIT_OK


def _cmd_calibrate(args: argparse.Namespace) -> int:
    from mpi4py import MPI

    from breakwater.statics.calibrate import HorizontalStiffness

    comm = MPI.COMM_WORLD
    case = _load(args, static=True)  # (no [time] needed: a static solve)
    cal = case.calibration
    if not cal.body or not cal.structure:
        raise CaseError("calibration.body/calibration.structure: the case does not say "
                        "which body to calibrate (set them with --set)")
    target = args.target if args.target is not None else cal.stiffness
    if target is None:
        raise CaseError("calibration.stiffness: no target stiffness (give --target K_x)")
    L = case.out_of_plane_length
    with shared_tempdir(comm, "breakwater-cal-") as folder:
        data = case.read_mesh(comm, folder)
    r = case.calibrate(data, target)
    # Independent check: a new model built with the calibrated modulus.
    model = case.build_model(data, {r.body: r.shear_modulus}, dynamic=False)
    problem = HorizontalStiffness(model, r.structure, cal.tangential_penalty)
    try:
        check = problem()
    finally:
        problem.destroy()
    q = args.quiet
    _say(f"calibration of the shear modulus of '{r.body}' to the horizontal stiffness of "
         f"'{r.structure}' (case '{case.name}')", q)
    if len(case.gravity) == 3:  # 3D: the model's own stiffness, nothing per metre
        _say(f"  target   K_x = {target:.6g} N/m", q)
        _say(f"  G        = {r.shear_modulus:.6g} Pa  ({r.iterations} stiffness solves)", q)
        _say(f"  achieved K_x = {r.stiffness:.6g} N/m (relative error "
             f"{r.relative_error:.2e}, tolerance {cal.tolerance:.1e})", q)
        _say(f"  check    K_x = {check:.6g} N/m from a new model with this G (relative "
             f"error {abs(check - r.target) / r.target:.2e})", q)
    elif cal.stiffness_basis == "block":
        _say(f"  target   K_x = {target:.6g} N/m over {L:g} m out of plane = "
             f"{r.target:.6g} N/m per m", q)
    else:
        _say(f"  target   K_x = {target:.6g} N/m per m (calibration.stiffness_basis = "
             '"metre")', q)
    if len(case.gravity) == 2:
        _say(f"  G        = {r.shear_modulus:.6g} Pa  ({r.iterations} stiffness solves)", q)
        _say(f"  achieved K_x = {r.stiffness:.6g} N/m per m = {r.stiffness * L:.6g} N/m "
             f"(relative error {r.relative_error:.2e}, tolerance {cal.tolerance:.1e})", q)
        _say(f"  check    K_x = {check:.6g} N/m per m from a new model with this G "
             f"(relative error {abs(check - r.target) / r.target:.2e})", q)
    if _rank() == 0 and args.quiet:
        print(f"{r.shear_modulus:.10g}")
    return EXIT_OK


def _cmd_sweep(args: argparse.Namespace) -> int:
    from mpi4py import MPI

    from breakwater.casefile.case import case_sources
    from breakwater.studies.studyfile import load_study
    from breakwater.studies.sweep import run_study

    study = load_study(args.study, args.set or [], max_points=args.max_points)
    out = args.out if args.out is not None else pathlib.Path("results") / study.name
    where = "--out" if args.out is not None else "the study's folder"
    _check_output(out, where, [study.path, *case_sources(study.base)], MPI.COMM_WORLD,
                  files.STUDY_PATTERNS, "the study's outputs", study=True)
    if not args.verbose:  # the cases' own messages: one line per case instead
        logging.getLogger("breakwater").setLevel(logging.CRITICAL)
    outcome = run_study(study, args.out, ranks_per_case=args.ranks_per_case,
                        quiet=args.quiet)
    return EXIT_OK if outcome.complete else EXIT_FAILED


UNMESHED_PROBES = (
    "# show-case reads the case, not the mesh: the probes' points (output.probes,\n"
    "# output.pair_probes) are not checked here against their bodies and interfaces;\n"
    "# run checks them once the mesh is read (a point outside: refused in one line)\n")
"""What ``show-case`` prints above a case with probes. Checking their points needs the
mesh: a generated one takes seconds to build (goda3d: 8 s), which ``show-case``, a
reading of the case, does not spend; it said nothing, and a probe outside the bodies
looked accepted until ``run`` refused it."""


def _cmd_show_case(args: argparse.Namespace) -> int:
    if args.reference:
        from breakwater.casefile.case import case_reference

        _say(case_reference())
        return EXIT_OK
    import tomli_w

    case = _load(args)
    text = tomli_w.dumps(case.resolved())
    if case.output.probes or case.output.pair_probes:  # (a comment: still TOML)
        text = UNMESHED_PROBES + text
    if _rank() == 0:
        sys.stdout.write(text)
        sys.stdout.flush()
    return EXIT_OK


# --- the parser ---------------------------------------------------------------------

def _parser() -> argparse.ArgumentParser:
    flags = _Parser(add_help=False)
    flags.add_argument("--set", action="append", metavar="KEY=VALUE",
                       help="override a case field by its dotted path, e.g. "
                            "time.dt=5e-5 or bodies.mound.density=1800; a table value "
                            "merges into the case's table (damping={alpha=0.1} keeps "
                            "beta) or adds a new entry (fixed.caisson_rear={components=[0]})"
                            " (repeatable; sweep: for every case)")
    noise = flags.add_mutually_exclusive_group()
    noise.add_argument("-q", "--quiet", action="store_true", help="print only warnings "
                       "and errors")
    noise.add_argument("-v", "--verbose", action="store_true", help="print debug messages")
    flags.add_argument("--debug", action="store_true",
                       help="show the traceback of errors")
    common = _Parser(add_help=False, parents=[flags])
    common.add_argument("case", nargs="?", default=None, metavar="CASE",
                        help="case file (TOML) or built-in case name (default: goda)")

    parser = _Parser(
        prog=PROG, description="Dynamic frictional contact of deformable bodies: a "
        "breakwater caisson on a gravel mound struck by a pendulum (Goda 1994; "
        "Stickle et al. 2011).")
    parser.add_argument("--version", action="version", version=f"breakwater {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("run", parents=[common], help="run a case",
                       description="Static equilibrium, then GN22 time stepping; writes "
                       "the results to the output folder.")
    p.add_argument("--out", type=pathlib.Path, default=None, metavar="DIR",
                   help="output folder (default: the case's output.directory, "
                        "results/<case name>)")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress bar (default: only when stderr is a terminal)")
    p.add_argument("--resume", action="store_true",
                   help="continue the interrupted run of the output folder from its "
                        "checkpoint (the case must be the same; see "
                        "output.checkpoint_interval)")
    p.add_argument("--auto-resume", action="store_true",
                   help="resume when the output folder holds a checkpoint of this case, "
                        "else start afresh: one batch script for a job's first "
                        "submission and its requeues (a plain run clears the folder)")
    p.set_defaults(func=_cmd_run)

    p = sub.add_parser("mesh", parents=[common], help="write the case's mesh",
                       description="Generate (or convert) the case's mesh; the format "
                       "follows the suffix: .msh, .xdmf, .vtu, ... A case reads the .msh, "
                       "and the .xdmf (dolfinx's, with x.h5 beside it and the groups' "
                       "names) as its mesh.source; the others are for viewing.")
    p.add_argument("--out", type=pathlib.Path, required=True, metavar="FILE",
                   help="output mesh file")
    p.set_defaults(func=_cmd_mesh)

    p = sub.add_parser("calibrate", parents=[common],
                       help="calibrate a shear modulus to a horizontal stiffness",
                       description="Find the shear modulus of calibration.body for which "
                       "calibration.structure has the horizontal stiffness K_x, and check "
                       "it with an independent solve.")
    p.add_argument("--target", type=float, default=None, metavar="K_X",
                   help="target stiffness of the real structure, N/m (default: "
                        "calibration.stiffness), divided by out_of_plane_length")
    p.set_defaults(func=_cmd_calibrate)

    p = sub.add_parser("sweep", parents=[flags], help="run a parameter study",
                       description="Run every point of a study file (a base case and the "
                       "case keys to vary) as a case in its own folder, with sweep.csv "
                       "and figures; under mpiexec the ranks form groups running one case "
                       "each, handed out dynamically. Rerunning skips the finished cases. "
                       "Exit status 0 when every case finished, 1 otherwise.")
    p.add_argument("study", type=pathlib.Path, metavar="STUDY",
                   help="study file (TOML; see breakwater.studies.studyfile)")
    p.add_argument("--out", type=pathlib.Path, default=None, metavar="DIR",
                   help="the study's folder (default: results/<study name>)")
    p.add_argument("--ranks-per-case", type=int, default=1, metavar="K",
                   help="ranks of each group running a case (must divide the number of "
                        "ranks; default 1; a warning when the ranks exceed the cores, or "
                        "the host is busy: such cases crawl)")
    p.add_argument("--max-points", type=int, default=MAX_POINTS, metavar="N",
                   help=f"refuse a study of more points (default {MAX_POINTS}): every "
                        "point's case is read before the study starts, and each runs")
    p.set_defaults(func=_cmd_sweep)

    p = sub.add_parser("show-case", parents=[common], help="print the resolved case",
                       description="Print the fully resolved case (TOML, defaults "
                       "filled), or the reference of every key.")
    p.add_argument("--reference", action="store_true",
                   help="print the table of every case key (type, unit, default)")
    p.set_defaults(func=_cmd_show_case)
    return parser


def _report(error: BaseException) -> None:
    if _rank() == 0:
        line = " ".join(str(error).split()) or type(error).__name__
        print(f"breakwater: error: {line}", file=sys.stderr, flush=True)


@contextmanager
def _signals(args: argparse.Namespace) -> Iterator[None]:
    """SIGTERM and SIGINT end a command that computes in one line (exit status 1).

    ``show-case`` reads a case and prints it: nothing to stop (and no PETSc to load).
    """
    if getattr(args, "command", None) == "show-case":
        yield
        return
    from mpi4py import MPI

    from breakwater.common.commandsignals import signals_end_the_command

    with signals_end_the_command(MPI.COMM_WORLD):
        yield


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status."""
    parser = _parser()
    try:
        args = _parse(parser, argv)
    except SystemExit as e:  # usage errors (2) and --help/--version (0)
        return int(e.code or 0) if not isinstance(e.code, str) else EXIT_INPUT
    from breakwater.outputs.checkpoint import CheckpointError

    try:
        with _logging(args), _signals(args):
            return int(args.func(args))
    except (CaseError, MeshError, CheckpointError) as e:
        if args.debug:
            raise
        _report(e)
        return EXIT_INPUT
    except BreakwaterError as e:
        if args.debug:
            raise
        _report(e)
        return EXIT_FAILED
    except KeyboardInterrupt:
        if args.debug:
            raise
        _report(KeyboardInterrupt("interrupted"))
        return 130
    except OSError as e:  # not met where files are written (those say cannot write)
        if args.debug:
            raise
        _report(OSError(f"{e.filename}: {e.strerror}" if e.filename and e.strerror
                        else str(e)))
        return EXIT_FAILED
