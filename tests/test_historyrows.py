"""The history rows kept in memory as one array (breakwater.outputs.historyrows).

A run keeps every history row for its summary and a storm's record; they used to be
Python dicts (about 5 KB a row on the prototype storm: 1.9 GB for 1000 waves). These
tests check that the array store gives the same rows and columns as the dicts, that
the summary and the storm record read it the same way, and its memory per row.
"""

from __future__ import annotations

import gc
import math
import sys

import numpy as np
import pytest
from mpi4py import MPI

from breakwater.outputs.historyrows import HistoryRows, column
from breakwater.outputs.stormrecord import small_sliding_warning, storm_record
from breakwater.outputs.summary import dynamic_summary, energy_summary

pytestmark = pytest.mark.serial


@pytest.fixture(autouse=True)
def _collect():
    yield
    gc.collect()
    MPI.COMM_WORLD.Barrier()


COLUMNS = ("t", "p_ux", "p_uy", "c_slip", "c_opening", "kinetic", "strain", "penalty",
           "external_work", "balance_error")


def _rows(n: int, seed: int = 0) -> list[dict[str, float]]:
    rng = np.random.default_rng(seed)
    values = rng.standard_normal((n, len(COLUMNS)))
    values[:, 0] = np.cumsum(rng.uniform(0.01, 0.1, n))  # t increasing
    return [dict(zip(COLUMNS, map(float, v), strict=True)) for v in values]


def test_rows_and_columns_are_the_dicts():
    dicts = _rows(1000)  # past the first allocation (64 rows): grown four times
    rows = HistoryRows(COLUMNS)
    for d in dicts:
        rows.append({**d, "ignored": 1.0})
    assert len(rows) == 1000 and bool(rows)
    assert rows[0] == dicts[0] and rows[-1] == dicts[-1] and rows[517] == dicts[517]
    assert all(type(v) is float for v in rows[3].values())
    for name in COLUMNS:
        assert np.array_equal(rows.column(name), column(dicts, name))  # bit for bit
    tail = rows[1:]
    assert isinstance(tail, HistoryRows) and len(tail) == 999 and tail[0] == dicts[1]
    assert np.array_equal(tail.column("t"), rows.column("t")[1:])
    with pytest.raises(IndexError):
        rows[1000]
    with pytest.raises(KeyError):
        rows.column("missing")
    assert np.array_equal(rows.column("missing", 0.5), np.full(1000, 0.5))
    assert np.array_equal(column(dicts, "missing", 0.5), np.full(1000, 0.5))
    with pytest.raises(KeyError):
        rows.append({"t": 1.0})  # a row without every column is refused
    with pytest.raises(ValueError):
        rows.column("t")[0] = 1.0  # the views are read-only


def test_a_slice_appends_without_changing_its_parent():
    rows = HistoryRows(COLUMNS, _rows(10))
    head = rows[:5]
    head.append(rows[9])
    assert head[5] == rows[9] and rows[5] != rows[9] and len(rows) == 10


def test_rows_from_an_array_as_a_resume_reads_them():
    dicts = _rows(50)
    values = np.array([[d[c] for c in COLUMNS] for d in dicts])
    rows = HistoryRows(COLUMNS, values)
    assert rows[-1] == dicts[-1]
    rows.append(dicts[0])
    assert len(rows) == 51 and rows[50] == dicts[0]
    with pytest.raises(ValueError):
        HistoryRows(COLUMNS, values[:, :3])


def test_memory_per_row():
    # 10 float64 columns: 80 bytes a row, at most twice that while it grows (here about
    # 130); the dicts take 512 bytes a row here (the dict and its float objects; with
    # the prototype storm's 50 columns, about 3.5 KB).
    dicts = _rows(10_000)
    rows = HistoryRows(COLUMNS, dicts)
    per_row = rows._data.nbytes / len(rows)
    as_dicts = sum(sys.getsizeof(d) + sum(sys.getsizeof(v) for v in d.values())
                   for d in dicts) / len(dicts)
    assert per_row <= 2 * 8 * len(COLUMNS)
    assert as_dicts > 3 * per_row


def test_summaries_read_the_array_as_the_dicts():
    dicts = _rows(300, seed=1)
    rows = HistoryRows(COLUMNS, dicts)
    assert dynamic_summary(rows, ["p"], ["c"]) == dynamic_summary(dicts, ["p"], ["c"])
    assert energy_summary(rows) == energy_summary(dicts)
    assert energy_summary(HistoryRows(COLUMNS)) == energy_summary([])


def _storm_rows(n: int) -> list[dict[str, float]]:
    """Rows of a storm record's columns: three base probes of a pair, its penetration."""
    rng = np.random.default_rng(2)
    out = []
    for k in range(n):
        r = {"t": 0.05 * k, "pair_penetration": float(rng.uniform(0, 1e-6))}
        for name in ("lo", "hi", "mid"):
            r.update({f"s_{name}_{side}_{c}": float(rng.standard_normal() * 1e-3)
                      for side in ("slave", "master") for c in ("ux", "uy")})
            r[f"s_{name}_slip"] = float(rng.standard_normal() * 1e-3)
        out.append(r)
    return out


def test_storm_record_reads_the_array_as_the_dicts():
    dicts = _storm_rows(200)  # t = 0 … 9.95 s: waves of 2 s, the fifth unfinished
    rows = HistoryRows(tuple(dicts[0]), dicts)
    storm = {"waves": [{"height": 0.1 * k, "period": 2.0, "start": 2.0 * k + 0.01,
                        "front_force_per_p1": 0.3} for k in range(5)],
             "record": {"lo": "s_lo", "hi": "s_hi", "mid": "s_mid", "sign": 1,
                        "landward": 1.0, "length": 2.0, "penetration": "pair_penetration",
                        "penalty": 1e9, "conforming": True, "pair": "pair"}}
    p1 = math.sin
    waves, block = storm_record(rows, storm, p1)
    assert (waves, block) == storm_record(dicts, storm, p1)
    assert len(waves) == 4 and block["waves_finished"] == 4
    # Wave 2 by hand: (2.01, 4.01 s] holds rows 41 … 80; row 40 (t = 2 s) is before it.
    mid = np.array([d["s_mid_slave_ux"] - d["s_mid_master_ux"] for d in dicts])
    assert waves[1]["sliding"] == mid[80] - mid[40]
    θ = np.array([(d["s_hi_slave_uy"] - d["s_lo_slave_uy"]) / 2.0 for d in dicts])
    assert waves[1]["rocking"] == np.abs(θ[41:81] - θ[0]).max()
    assert waves[1]["max_contact_pressure"] == 1e9 * max(
        d["pair_penetration"] for d in dicts[41:81])
    assert small_sliding_warning(rows, storm["record"], 1e-3) == \
        small_sliding_warning(dicts, storm["record"], 1e-3)


def test_read_history_takes_the_file_or_the_run_folder(tmp_path):
    """``read_history`` of a run's output folder reads its history.csv (a notebook's
    natural call, ``read_history(out)``, failed with IsADirectoryError)."""
    from breakwater.common.files import HISTORY, read_history

    dicts = _rows(3)
    (tmp_path / HISTORY).write_text(",".join(COLUMNS) + "\n" + "".join(
        ",".join(repr(d[c]) for c in COLUMNS) + "\n" for d in dicts), encoding="utf-8")
    for given in (tmp_path, str(tmp_path), tmp_path / HISTORY):
        read = read_history(given)
        assert list(read) == list(COLUMNS)
        for c in COLUMNS:
            assert read[c].tolist() == [d[c] for d in dicts]  # repr round-trips exactly
