"""Outputs that cannot be written, and outputs that would replace inputs.

Every command goes through :func:`breakwater.cli.main` in-process, serially and under
``mpiexec`` (every rank must return the same exit status: no hang). A problem found
before the run is one line ``breakwater: error: ...`` and exit status 2; a write that
fails during a run ends it with exit status 1, one line ``cannot write <path>:
<reason>`` and, when ``summary.json`` can still be written, ``"status": "failed"``.

The tests run as root, where ``chmod`` does not stop writes, so an unwritable folder
is made in ways that work for root: a path under a regular file (a real ``ENOTDIR``
from the file system), a name longer than 255 bytes (a real ``ENAMETOOLONG``), and a
read-only folder by monkeypatching ``open`` in :mod:`breakwater.common.files` to raise
``PermissionError(EACCES)``. A full disk is simulated by monkeypatching a writer
(``HistoryWriter._write``, the figures, ``os.replace``) to raise ``OSError(ENOSPC)``.
"""

from __future__ import annotations

import errno
import io
import json
import os
import pathlib
from typing import Any

import pytest
from blocks import two_block_case, two_rectangles
from mpi4py import MPI

from breakwater import cli
from breakwater.casefile.case import load_case
from breakwater.common import files
from breakwater.common.errors import CaseError
from breakwater.outputs import figures
from breakwater.outputs.writers import HistoryWriter
from breakwater.run import simulation
from breakwater.studies.studyfile import load_study
from breakwater.studies.sweep import run_study

COMM = MPI.COMM_WORLD
FULL = os.strerror(errno.ENOSPC)  # "No space left on device"


def _case(folder: pathlib.Path, name: str = "tiny.toml", head: str = "") -> pathlib.Path:
    """A two-block case of 3 steps on a coarse mesh (about 1 s), written in ``folder``.

    Four facets along the interface: with two, the run warned that the static contact
    is not resolved, a line beside the one-line errors these tests read.
    """
    mesh = two_rectangles(folder / "blocks.msh", COMM, (1.0, 0.5), (1.0, 0.5), 0.25)
    path = folder / name
    if COMM.rank == 0:
        path.write_text(two_block_case(mesh.name, head=head, tail="[output]\n"
                                       "field_interval = 0\nfigures = false\n")
                        .replace("end_time = 1e-3", "end_time = 3e-4"))
    COMM.barrier()
    return path


def _study(folder: pathlib.Path, case: pathlib.Path) -> pathlib.Path:
    path = folder / "study.toml"
    if COMM.rank == 0:
        path.write_text(f'base = "{case.name}"\n[grid]\n"time.dt" = [1e-4]\n')
    COMM.barrier()
    return path


def _main(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    code = cli.main([*args, "--quiet"])
    err = capsys.readouterr().err
    if COMM.rank == 0:
        assert "Traceback" not in err, err
    return code, err


def _refused(code: int, err: str, phrase: str) -> None:
    """Exit status 2 and one line ``breakwater: error: ...`` holding ``phrase``."""
    assert code == 2, err
    if COMM.rank == 0:
        assert err.count("\n") == 1 and err.startswith("breakwater: error: "), err
        assert phrase in err, err


def _summary(out: pathlib.Path) -> dict:
    return json.loads((out / files.SUMMARY).read_text())


# --- a full disk during and at the end of a run -------------------------------------------

def test_full_disk_during_the_run(shared_dir, capsys, monkeypatch):
    """history.csv's 4th row meets a full disk: exit 1, one line, summary failed."""
    case, out = _case(shared_dir), shared_dir / "out"
    write, lines = HistoryWriter._write, []

    def full(self: HistoryWriter, line: str) -> None:
        lines.append(line)
        if len(lines) > 4:  # the header, the static row, two steps
            raise OSError(errno.ENOSPC, FULL)
        write(self, line)

    monkeypatch.setattr(HistoryWriter, "_write", full)
    code, err = _main(["run", str(case), "--out", str(out), "--no-progress"], capsys)
    assert code == 1, err
    if COMM.rank == 0:
        reason = f"cannot write {out / files.HISTORY}: {FULL}"
        assert err == f"breakwater: error: {reason}\n", err  # one line with --quiet
        summary = _summary(out)
        assert summary["status"] == "failed" and summary["error"] == reason, summary
        assert len((out / files.HISTORY).read_text().splitlines()) == 4


def test_no_byte_left_for_the_summary(shared_dir, capsys, monkeypatch):
    """history.csv's 4th row meets a disk with no byte left (another process filled it):
    the summary says failed all the same, written in the room the folder's lock file
    kept for it (:data:`~breakwater.common.folderlock.RESERVE`), and the lock file goes.

    Before: the summary could not be rewritten and said ``running`` after the run had
    failed (measured on an 8 MB tmpfs that another file filled at that row; with the
    room kept it says ``failed``). Here the disk is full from that row on: a file
    written after it fits only in the bytes the lock file gave back since (its allocated
    size then, less its size now), less the bytes written since.
    """
    from breakwater.common import folderlock

    case, out = _case(shared_dir), shared_dir / "out"
    lock = out / folderlock.LOCK
    write, lines, disk = HistoryWriter._write, [], {"kept": -1, "used": 0}

    def allocated() -> int:
        return lock.stat().st_blocks * 512 if lock.exists() else 0

    def full(self: HistoryWriter, line: str) -> None:
        lines.append(line)
        if len(lines) > 4:  # the header, the static row, two steps
            disk["kept"] = allocated()
            assert disk["kept"] >= folderlock.RESERVE
            raise OSError(errno.ENOSPC, FULL)
        write(self, line)

    class Full(io.FileIO):
        def write(self, data: Any) -> int:
            if len(data) > disk["kept"] - allocated() - disk["used"]:
                raise OSError(errno.ENOSPC, FULL)
            disk["used"] += len(data)
            return super().write(data)

    def full_open(path: Any, mode: str = "r", **kwargs: Any) -> Any:
        if disk["kept"] >= 0 and mode == "wb":
            return Full(path, "w")
        return open(path, mode, **kwargs)

    monkeypatch.setattr(HistoryWriter, "_write", full)
    monkeypatch.setattr(files, "open", full_open, raising=False)
    code, err = _main(["run", str(case), "--out", str(out), "--no-progress"], capsys)
    assert code == 1, err
    if COMM.rank == 0:
        reason = f"cannot write {out / files.HISTORY}: {FULL}"
        assert err == f"breakwater: error: {reason}\n", err
        summary = _summary(out)
        assert summary["status"] == "failed" and summary["error"] == reason, summary
        assert 0 < disk["used"] < folderlock.RESERVE
        assert not lock.exists() and not list(out.glob(".*.tmp*"))


def test_full_disk_in_the_file_system(shared_dir, capsys, monkeypatch):
    """history.csv meets a full disk in the file system, below Python's buffer: one line.

    The kernel writes what fits (part of a row) and then refuses (ENOSPC); Python's
    buffer keeps the rest, and closing the file tries it again. The close logged a
    warning ``cannot write .../history.csv: No space left on device`` above the run's
    error, the same words twice (measured on a 700 kB tmpfs). The file is made to fail
    at its own bytes: those of the whole run's history less 100 (the last row cut).
    """
    from breakwater.outputs import writers

    case = _case(shared_dir)
    code, err = _main(["run", str(case), "--out", str(shared_dir / "whole"),
                       "--no-progress"], capsys)
    assert code == 0, err
    size = COMM.bcast((shared_dir / "whole" / files.HISTORY).stat().st_size
                      if COMM.rank == 0 else None)
    out = shared_dir / "out"

    class Full(io.FileIO):
        """A file on a disk with ``size - 100`` bytes free (a real partial write)."""

        left = size - 100

        def write(self, data: Any) -> int:
            if Full.left <= 0:
                raise OSError(errno.ENOSPC, FULL)
            n = min(len(data), Full.left)
            Full.left -= n
            return super().write(bytes(data)[:n])

    def full_open(path: Any, mode: str = "r", **kwargs: Any) -> Any:
        if pathlib.Path(path) == out / files.HISTORY and mode == "w":
            return io.TextIOWrapper(io.BufferedWriter(Full(path, "w")), **kwargs)
        return open(path, mode, **kwargs)

    monkeypatch.setattr(writers, "open", full_open, raising=False)
    code, err = _main(["run", str(case), "--out", str(out), "--no-progress"], capsys)
    assert code == 1, err
    if COMM.rank == 0:
        reason = f"cannot write {out / files.HISTORY}: {FULL}"
        assert err == f"breakwater: error: {reason}\n", err
        assert _summary(out)["status"] == "failed"
        assert not (out / files.HISTORY).read_text().endswith("\n")  # the row cut


def test_full_disk_at_the_end(shared_dir, capsys, monkeypatch):
    """The figures meet a full disk after the last step: the summary says failed."""
    case, out = _case(shared_dir), shared_dir / "out"

    def full(directory: pathlib.Path) -> list[pathlib.Path]:
        (directory / files.FIGURES).mkdir(exist_ok=True)
        with files.writing(directory / files.FIGURES / "history.png"):
            raise OSError(errno.ENOSPC, FULL)

    monkeypatch.setattr(figures, "make_figures", full)
    code, err = _main(["run", str(case), "--out", str(out), "--no-progress",
                       "--set", "output.figures=true"], capsys)
    assert code == 1, err
    if COMM.rank == 0:
        reason = f"cannot write {out / files.FIGURES / 'history.png'}: {FULL}"
        assert err.splitlines()[-1] == f"breakwater: error: {reason}", err
        summary = _summary(out)
        assert summary["status"] == "failed" and summary["error"] == reason, summary


def test_full_disk_from_the_start(shared_dir, capsys, monkeypatch):
    """No file can be replaced at all (os.replace raises ENOSPC): exit 1, one line."""
    case, out = _case(shared_dir), shared_dir / "out"

    def full(src: object, dst: object) -> None:
        raise OSError(errno.ENOSPC, FULL)

    monkeypatch.setattr(files.os, "replace", full)
    code, err = _main(["run", str(case), "--out", str(out), "--no-progress"], capsys)
    assert code == 1, err
    if COMM.rank == 0:
        assert err.splitlines()[-1] == (f"breakwater: error: cannot write "
                                        f"{out / files.CASE}: {FULL}"), err
        assert not (out / files.SUMMARY).exists()
        assert not list(out.glob(".*.tmp*"))  # no temporary file left behind


@pytest.mark.serial  # under MPI ADIOS2 hangs on a failed write: the next test's check
def test_full_disk_in_a_paraview_file(shared_dir, capsys, monkeypatch):
    """A field file meets a real write error of ADIOS2 (a file-size limit, EFBIG: the
    path of a full disk) at its third time: exit 1, one line, the summary failed, the
    file readable up to its last whole time, and --resume goes on from the checkpoint.

    Before: a traceback of ADIOS2's coloured RuntimeError, then the process aborted
    (``terminate called ...``, exit 134) when the failed writer's C++ destructor threw
    again, with ``summary.json`` left ``running`` (measured on a 3 MB tmpfs).
    """
    import resource

    import dolfinx.io

    from breakwater.outputs.fieldgrids import field_times, read_fields

    case, out = _case(shared_dir), shared_dir / "out"
    args = ["run", str(case), "--out", str(out), "--no-progress", "--set",
            "output.field_interval=1", "--set", "output.checkpoint_interval=1"]
    write, times = dolfinx.io.VTXWriter.write, []
    limit = resource.getrlimit(resource.RLIMIT_FSIZE)

    def limited(self: dolfinx.io.VTXWriter, t: float) -> None:
        times.append(t)  # fields_a.bp is written first at each time
        if len(set(times)) != 3 or times.count(t) > 1:
            return write(self, t)
        # Python ignores SIGXFSZ: a write past the limit fails with EFBIG.
        size = (out / "fields_a.bp" / "data.0").stat().st_size
        resource.setrlimit(resource.RLIMIT_FSIZE, (size, limit[1]))
        try:
            return write(self, t)
        finally:
            resource.setrlimit(resource.RLIMIT_FSIZE, limit)

    monkeypatch.setattr(dolfinx.io.VTXWriter, "write", limited)
    code, err = _main(args, capsys)
    assert code == 1, err
    if COMM.rank == 0:
        reason = f"cannot write {out / 'fields_a.bp'}: {os.strerror(errno.EFBIG)}"
        assert err == f"breakwater: error: {reason}\n", err
        summary = _summary(out)
        assert summary["status"] == "failed" and summary["error"] == reason, summary
        assert summary["checkpoint"]["steps"] == 1  # the last whole step's
        assert field_times(out, "a").tolist() == pytest.approx([0.0, 1e-4])
        assert read_fields(out, "a").field_data["time"][0] == pytest.approx(1e-4)
    COMM.barrier()
    monkeypatch.setattr(dolfinx.io.VTXWriter, "write", write)
    code, err = _main([*args, "--resume"], capsys)
    assert code == 0, err
    if COMM.rank == 0:
        assert _summary(out)["status"] == "finished"
        assert field_times(out, "a").tolist() == pytest.approx([0.0, 1e-4, 2e-4, 3e-4])


def test_no_room_for_the_next_paraview_time(shared_dir, capsys, monkeypatch):
    """The disk has no room for one more field write (twice the mean bytes of a write and
    4 MB): the run stops before ADIOS2 fails (which hangs under MPI), in one line, with
    the summary failed, the checkpoint of the step before, and room left for them."""
    import shutil

    from breakwater.outputs import vtxfiles
    from breakwater.outputs.fieldgrids import field_times

    case, out = _case(shared_dir), shared_dir / "out"
    usage, calls = shutil.disk_usage, []

    def nearly_full(path: Any) -> Any:
        calls.append(path)  # (rank 0) the third time: 3 MB free
        total, used, free = usage(path)
        return type(usage(path))(total, used, 3_000_000 if len(calls) == 2 else free)

    monkeypatch.setattr(vtxfiles.shutil, "disk_usage", nearly_full)
    code, err = _main(["run", str(case), "--out", str(out), "--no-progress", "--set",
                       "output.field_interval=1", "--set", "output.checkpoint_interval=1"],
                      capsys)
    assert code == 1, err
    if COMM.rank == 0:
        assert err.count("\n") == 1, err
        assert err.startswith(f"breakwater: error: cannot write {out}: {FULL} (3 MB free; "
                              "the ParaView fields take about "), err
        summary = _summary(out)
        assert summary["status"] == "failed" and summary["error"] in err, summary
        assert summary["checkpoint"]["steps"] == 1
        assert field_times(out, "a").tolist() == pytest.approx([0.0, 1e-4])


def test_fields_that_will_not_fit_are_foreseen(shared_dir, capsys, monkeypatch):
    """After its second field write a run warns once, in one line, when the writes still
    planned will not fit on the disk (before: a long run learned it when the disk was
    full). Here the disk has room for the next write (and no margin) but not for the 9
    more that 10 steps write."""
    import shutil

    from breakwater.outputs import vtxfiles

    case, out = _case(shared_dir), shared_dir / "out"
    usage, calls = shutil.disk_usage, []

    def tight(path: Any) -> Any:
        calls.append(path)  # (rank 0) before the third write: what the fields hold + 1
        total, used, free = usage(path)
        held = sum(f.stat().st_size for f in out.glob("*.bp/*"))
        return type(usage(path))(total, used, held + 1 if len(calls) == 2 else free)

    monkeypatch.setattr(vtxfiles.shutil, "disk_usage", tight)
    monkeypatch.setattr(vtxfiles, "MARGIN", 0)
    code, err = _main(["run", str(case), "--out", str(out), "--no-progress", "--set",
                       "output.field_interval=1", "--set", "time.end_time=1e-3"], capsys)
    assert code == 0, err
    if COMM.rank == 0:
        lines = [line for line in err.splitlines() if "ParaView fields will take" in line]
        assert len(lines) == 1 and "(9 writes of " in lines[0], err
        assert lines[0].endswith("the run will stop when it is full (raise "
                                 "output.field_interval)"), err


# --- output folders that cannot be written, refused before the run ------------------------

@pytest.mark.timeout(300)
@pytest.mark.parametrize("which", ["running", "final"])
def test_full_disk_in_a_study_record(which, shared_dir, capsys, monkeypatch):
    """The record ``sweep_case.json`` of the first case meets a full disk, when the case
    starts (``running``) or when it ends (``final``): the study stops as a run does, in
    one line, exit 1, on every rank, its table saying the case failed with that line;
    a group that runs another case (2 ranks, one rank a case) finishes it. Run again,
    the study goes on (a case that had finished recorded from its summary).

    Before: the line and exit 1, but sweep.csv said the case was ``pending``; on 2
    ranks the study hung (the failing rank left the others waiting in its end).
    """
    import csv

    case, out = _case(shared_dir), shared_dir / "out"
    study = shared_dir / "study.toml"
    if COMM.rank == 0:
        study.write_text(f'base = "{case.name}"\n[grid]\n"time.dt" = [1e-4, 1.5e-4]\n')
    COMM.barrier()
    first = "case-0000_dt=0.0001"
    record = out / first / "sweep_case.json"
    replace, seen = os.replace, []

    def full(src: Any, dst: Any) -> None:
        if str(dst) == str(record):
            seen.append(dst)  # 1: "running", 2: the final record
            if len(seen) == {"running": 1, "final": 2}[which]:
                raise OSError(errno.ENOSPC, FULL)
        replace(src, dst)

    monkeypatch.setattr(files.os, "replace", full)
    args = ["sweep", str(study), "--out", str(out), "--ranks-per-case", "1"]
    code, err = _main(args, capsys)
    assert code == 1, err
    reason = f"cannot write {record}: {FULL}"
    if COMM.rank == 0:
        assert err == f"breakwater: error: {reason}\n", err
        with open(out / "sweep.csv", newline="") as f:
            rows = {r["folder"]: r for r in csv.DictReader(f)}
        assert rows[first]["status"] == "failed" and rows[first]["error"] == reason, rows
        other = "finished" if COMM.size > 1 else "pending"
        assert rows["case-0001_dt=0.00015"]["status"] == other, rows
    COMM.barrier()
    monkeypatch.setattr(files.os, "replace", replace)
    code, err = _main(args, capsys)
    assert code == 0, err
    if COMM.rank == 0:
        with open(out / "sweep.csv", newline="") as f:
            assert [r["status"] for r in csv.DictReader(f)] == ["finished"] * 2


def _commands(case: pathlib.Path, study: pathlib.Path, out: pathlib.Path
              ) -> dict[str, list[str]]:
    return {"run": ["run", str(case), "--out", str(out), "--no-progress"],
            "sweep": ["sweep", str(study), "--out", str(out)],
            "mesh": ["mesh", str(case), "--out", str(out / "mesh.msh")]}


@pytest.mark.parametrize("command", ["run", "sweep", "mesh"])
def test_out_under_a_file(command, shared_dir, capsys):
    """An output path under a regular file (ENOTDIR, even for root): exit 2."""
    case = _case(shared_dir)
    study = _study(shared_dir, case)
    out = case / "out"  # the case file is a file, not a folder
    code, err = _main(_commands(case, study, out)[command], capsys)
    _refused(code, err, "is a file, not a folder")


@pytest.mark.parametrize("command", ["run", "sweep", "mesh"])
def test_read_only_out(command, shared_dir, capsys, monkeypatch):
    """A folder where files cannot be created (open raises EACCES, as for a read-only
    folder; chmod does not stop root): exit 2, naming the folder."""
    case = _case(shared_dir)
    study = _study(shared_dir, case)
    out = shared_dir / "out"
    if COMM.rank == 0:
        out.mkdir()
    COMM.barrier()

    def denied(path: object, *args: object, **kwargs: object) -> None:
        raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(path))

    monkeypatch.setattr(files, "open", denied, raising=False)
    code, err = _main(_commands(case, study, out)[command], capsys)
    _refused(code, err, f"cannot write {out}: Permission denied")
    if COMM.rank == 0:
        assert list(out.iterdir()) == []


@pytest.mark.parametrize("command", ["run", "sweep"])
def test_out_is_a_file(command, shared_dir, capsys):
    """--out naming a file: exit 2 for run and sweep alike."""
    case = _case(shared_dir)
    study = _study(shared_dir, case)
    code, err = _main(_commands(case, study, case)[command], capsys)
    _refused(code, err, "not a folder (a file of that name exists)")


def test_out_name_too_long(shared_dir, capsys):
    """A folder name over 255 bytes (ENAMETOOLONG): exit 2."""
    case = _case(shared_dir)
    out = shared_dir / ("x" * 300) / "out"
    code, err = _main(["run", str(case), "--out", str(out), "--no-progress"], capsys)
    _refused(code, err, "File name too long")


# --- outputs never replace inputs ------------------------------------------------------------

@pytest.mark.parametrize("name", ["case.toml", "summary.json"])
def test_outputs_never_replace_the_case_file(name, shared_dir, capsys):
    """A case file in the output folder under an output's name: refused, untouched.

    ``summary.json`` is the base of the case run (``extends``): the files a case
    extends are inputs too.
    """
    base = _case(shared_dir, name=name, head="# my notes")
    case = base
    if name != "case.toml":
        case = shared_dir / "run.toml"
        if COMM.rank == 0:
            case.write_text(f'extends = "{name}"\n')
        COMM.barrier()
    before = base.read_bytes()
    code, err = _main(["run", str(case), "--out", str(shared_dir), "--no-progress"],
                      capsys)
    _refused(code, err, f"the outputs would write over the input {shared_dir / name}")
    assert base.read_bytes() == before
    assert not (shared_dir / files.HISTORY).exists()


def test_dotdot_name_without_out(shared_dir, capsys, monkeypatch):
    """name = ".." run without --out wrote into the working directory, over case.toml."""
    case = _case(shared_dir, name="case.toml", head='# my notes\nname = ".."')
    before = case.read_bytes()
    monkeypatch.chdir(shared_dir)
    code, err = _main(["run", "case.toml", "--no-progress"], capsys)
    _refused(code, err, "name: must not be '..'")
    assert case.read_bytes() == before
    assert not (shared_dir / files.SUMMARY).exists()


def test_sweep_never_replaces_its_study(shared_dir, capsys):
    """A study whose folder is the study file's own: sweep.csv is fine, a case folder
    named like the study's is not."""
    case = _case(shared_dir)
    folder = shared_dir / "case-0001_mine"
    if COMM.rank == 0:
        folder.mkdir()
        (folder / "study.toml").write_text(f'base = "../{case.name}"\n[grid]\n'
                                           '"time.dt" = [1e-4]\n')
    COMM.barrier()
    study = folder / "study.toml"
    code, err = _main(["sweep", str(study), "--out", str(shared_dir)], capsys)
    _refused(code, err, "the study's outputs would write over the input")
    assert study.is_file()


# --- a run's folder and a study's are not mixed -------------------------------------------

def _names(folder: pathlib.Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def test_a_study_is_refused_a_runs_folder(shared_dir, capsys):
    """sweep --out at a run's output folder wrote sweep.csv, the case folders and the
    study's figures beside the run's summary.json, history.csv and fields: refused in
    one line, the folder untouched (from Python: run_study alike)."""
    case = _case(shared_dir)
    study = _study(shared_dir, case)
    out = shared_dir / "run"
    code, err = _main(["run", str(case), "--out", str(out), "--no-progress"], capsys)
    assert code == 0, err
    before = _names(out)
    code, err = _main(["sweep", str(study), "--out", str(out)], capsys)
    _refused(code, err, f"--out {out}: holds a run's outputs (summary.json), not a "
             "study's: the study's would mix with them (choose another folder)")
    assert _names(out) == before
    with pytest.raises(CaseError, match=r"out .*: holds a run's outputs \(summary\.json\)"):
        run_study(load_study(study), out, quiet=True)
    assert _names(out) == before


def test_a_run_is_refused_a_studys_folder(shared_dir, capsys):
    """run --out at a study's folder wrote the run's outputs beside sweep.csv and the
    case folders: refused in one line, the folder untouched (from Python:
    simulation.run alike)."""
    case = _case(shared_dir)
    study = _study(shared_dir, case)
    out = shared_dir / "study"
    code, err = _main(["sweep", str(study), "--out", str(out)], capsys)
    assert code == 0, err
    before = _names(out)
    code, err = _main(["run", str(case), "--out", str(out), "--no-progress"], capsys)
    _refused(code, err, f"--out {out}: holds a study's outputs (sweep.csv), not a "
             "run's: the run's would mix with them (choose another folder)")
    assert _names(out) == before
    model, time, output, _ = load_case(case, [f"output.directory={json.dumps(str(out))}"]
                                       ).build(COMM)
    with pytest.raises(CaseError, match=r"output\.directory .*: holds a study's outputs"):
        simulation.run(model, time, output, report=False)
    assert _names(out) == before


# --- a crash of the numerical libraries ---------------------------------------------------

def test_petsc_error_ends_the_run_as_failed(shared_dir, capsys, monkeypatch):
    """A PETSc error in the static solve (here a real one: SNESSetTolerances refusing
    rtol = 1): exit 1, one line naming the routine, summary failed (was: a traceback,
    the summary left running)."""
    from petsc4py import PETSc

    from breakwater.run import begin

    case, out = _case(shared_dir), shared_dir / "out"

    def crash(model: object) -> None:
        snes = PETSc.SNES().create(COMM)
        try:
            snes.setTolerances(rtol=1.0)
        finally:
            snes.destroy()

    monkeypatch.setattr(begin, "initial_state", crash)
    code, err = _main(["run", str(case), "--out", str(out), "--no-progress"], capsys)
    assert code == 1, err
    if COMM.rank == 0:
        reason = ("PETSc error 63 in SNESSetTolerances(): Argument out of range; Relative "
                  "tolerance 1. must be non-negative and less than 1.0")
        assert err.splitlines()[-1] == f"breakwater: error: {reason}", err
        summary = _summary(out)
        assert summary["status"] == "failed" and summary["error"] == reason, summary


@pytest.mark.serial
def test_a_new_run_clears_the_earlier_runs_outputs(tmp_path: pathlib.Path) -> None:
    # A run into a finished run's folder left the old ParaView fields, figures and a
    # storm's waves.csv beside its own outputs (found by a user): the names a run
    # writes go, the user's other files stay; a folder without a run's summary.json
    # (not a run's folder) is left as it is.
    for name in ("summary.json", "history.csv", "waves.csv", "checkpoint.npz", "notes.txt"):
        (tmp_path / name).write_text("x")
    for folder in ("fields_a.bp", "contact_b.bp", "figures", "mesh"):
        (tmp_path / folder).mkdir()
        (tmp_path / folder / "data").write_text("x")
    (tmp_path / "figures" / "energy.png").write_text("x")
    assert files.clear_previous_run(tmp_path) == 7
    left = sorted(str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*"))
    assert left == ["figures", "figures/data", "mesh", "mesh/data", "notes.txt"]
    (tmp_path / "history.csv").write_text("x")
    assert files.clear_previous_run(tmp_path) == 0 and (tmp_path / "history.csv").exists()


def test_a_second_run_in_a_locked_folder_is_refused(shared_dir, capsys):
    """A folder whose lock another process holds (a run still building its case, before
    its summary names it): refused in one line naming the holder, nothing written.

    Before: the summary's check alone let a second run in while the first meshed and
    calibrated; both ran to "finished" in one folder (two Goda runs started 1 s apart).
    """
    import fcntl

    from breakwater.common import folderlock

    case, out = _case(shared_dir), shared_dir / "out"
    args = ["run", str(case), "--out", str(out), "--no-progress"]
    fd = None
    if COMM.rank == 0:  # another open file description: another process's lock
        out.mkdir()
        fd = os.open(out / folderlock.LOCK, os.O_RDWR | os.O_CREAT)
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        os.write(fd, json.dumps({"host": "node7", "pid": 4242, "started": "then"}).encode())
        os.posix_fallocate(fd, 0, folderlock.RESERVE)  # its room for the last summary
    COMM.barrier()
    try:
        code, err = _main(args, capsys)
        _refused(code, err, f"--out {out}: a run is going on in this folder (pid 4242 on "
                            "host node7, started then)")
        if COMM.rank == 0:
            assert sorted(p.name for p in out.iterdir()) == [folderlock.LOCK]
    finally:
        if fd is not None:
            os.close(fd)  # the other process ends: its lock goes with it
    COMM.barrier()
    code, err = _main(args, capsys)
    assert code == 0, err
    if COMM.rank == 0:
        assert _summary(out)["status"] == "finished"
        assert not (out / folderlock.LOCK).exists()  # given back, the file removed


@pytest.mark.timeout(300)
@pytest.mark.parametrize("where", ["start", "case", "lock", "end"])
def test_full_disk_in_the_study_table(where, shared_dir, capsys, monkeypatch):
    """``sweep.csv`` (or its lock file) meets a full disk on one rank: before the cases
    (``start``, rank 0), after a case (``case``: the last rank's group's table; the lock
    file ``lock``, there too) or at the end (``end``, rank 0). Every rank stops with exit
    1 and one line naming the file and the cause; no rank is left in a collective (the
    harness's time limit fails a hang). Run again with room, the study goes on.

    Before: after a case on 2 ranks, the failing rank left the loop with the error while
    the other went on to the end's broadcast (exit 0 on rank 0, 1 on rank 1, no line);
    the lock file's error was a bare ``OSError`` line.
    """
    from breakwater.studies import sweep, sweeptable

    case, out = _case(shared_dir), shared_dir / "out"
    study = shared_dir / "study.toml"
    if COMM.rank == 0:
        study.write_text(f'base = "{case.name}"\n[grid]\n"time.dt" = [1e-4, 1.5e-4]\n')
    COMM.barrier()
    table, lock = out / "sweep.csv", out / ".sweep.lock"
    rank = {"start": 0, "end": 0}.get(where, COMM.size - 1)  # the rank that fails
    state = {"calls": 0, "end": False, "done": False}
    write_table, replace, opened = sweep.write_table, os.replace, open

    def tracked(*args: Any) -> Any:
        state["end"] = len(args) == 5  # finish() passes the failures
        state["calls"] += 1
        return write_table(*args)

    def due() -> bool:
        """Whether this call is the one that fails (once)."""
        if state["done"] or COMM.rank != rank:
            return False
        due = {"start": state["calls"] == 1, "end": state["end"],
               "case": state["calls"] == (1 if COMM.rank else 2) and not state["end"],
               "lock": state["calls"] == (1 if COMM.rank else 2) and not state["end"]}
        state["done"] = due[where]
        return due[where]

    def full_replace(src: Any, dst: Any) -> None:
        if str(dst) == str(table) and where != "lock" and due():
            raise OSError(errno.ENOSPC, FULL)
        replace(src, dst)

    def full_open(path: Any, *args: Any, **kwargs: Any) -> Any:
        if str(path) == str(lock) and where == "lock" and due():
            raise OSError(errno.ENOSPC, FULL, str(path))
        return opened(path, *args, **kwargs)

    monkeypatch.setattr(sweep, "write_table", tracked)
    monkeypatch.setattr(files.os, "replace", full_replace)
    monkeypatch.setattr(sweeptable, "open", full_open, raising=False)
    args = ["sweep", str(study), "--out", str(out), "--ranks-per-case", "1"]
    code, err = _main(args, capsys)
    codes = COMM.allgather(code)
    assert codes == [1] * COMM.size, (codes, err)
    assert state["done"] == (COMM.rank == rank)
    name = lock if where == "lock" else table
    if COMM.rank == 0:
        assert err == f"breakwater: error: cannot write {name}: {FULL}\n", err
    COMM.barrier()
    monkeypatch.undo()
    code, err = _main(args, capsys)
    assert code == 0, err
    if COMM.rank == 0:
        import csv

        with open(table, newline="") as f:
            assert [r["status"] for r in csv.DictReader(f)] == ["finished"] * 2
