"""The notebook's progress line (breakwater.common.notebookprogress), without a kernel."""

from __future__ import annotations

from typing import Any

import pytest

from breakwater.common.notebookprogress import NotebookLine, in_kernel, progress_line

pytestmark = pytest.mark.serial  # text alone (no MPI): once is enough


class _Display:
    """IPython's display: records the texts shown and replaced."""

    def __init__(self) -> None:
        self.texts: list[str] = []

    def __call__(self, data: dict[str, str], raw: bool, display_id: bool) -> _Display:
        assert raw and display_id
        self.texts.append(data["text/plain"])
        return self

    def update(self, data: dict[str, str], raw: bool) -> None:
        self.texts.append(data["text/plain"])


def test_line_is_updated_at_intervals() -> None:
    """1000 steps over 10 s of wall time: about one update a second, and the last state."""
    now = [0.0]
    shown = _Display()
    line = NotebookLine("goda", 0.1, clock=lambda: now[0], display=shown)
    for k in range(1, 1001):
        now[0] = k * 0.01
        line.update(k * 1e-4, its=2)
    line.close()
    # The first line, one per EVERY = 1 s of the 10 s, and the closing one.
    assert len(shown.texts) == 1 + 10 + 1
    assert shown.texts[0].startswith("goda:   0% |")
    middle = shown.texts[5]  # at 5 s, t = 0.05 of 0.1 s: as long again to go
    assert "t = 0.05/0.1 s, 500 steps, 2.00 Newton iterations per step, 5 s elapsed, " \
           "about 5 s left" in middle
    assert shown.texts[-1] == ("goda: 100% |████████████████████| t = 0.1/0.1 s, 1000 "
                               "steps, 2.00 Newton iterations per step, 10 s elapsed")


@pytest.mark.parametrize(("t", "start", "left"), [(0.03, 0.02, "about 1 min 10 s left"),
                                                  (0.02, 0.02, "about ? left")])
def test_time_left_from_where_the_run_started(t: float, start: float, left: str) -> None:
    """A resumed run's rate counts from where it resumed: 0.01 s in 10 s, 0.07 s to go."""
    text = progress_line("c", t, start, 0.1, 10, 30, 10.0)
    assert text.endswith(f"10 s elapsed, {left}"), text


def test_no_kernel_here(monkeypatch: Any) -> None:
    """pytest is no Jupyter kernel; an IPython shell without a kernel neither."""
    assert not in_kernel()
    IPython = pytest.importorskip("IPython")
    shell = type("Shell", (), {"kernel": None})()
    monkeypatch.setattr(IPython, "get_ipython", lambda: shell)
    assert not in_kernel()
    shell.kernel = object()
    assert in_kernel()
