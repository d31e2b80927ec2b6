"""The progress line fits the terminal it is drawn on (issue 19, audit: it padded to 80 and cut at 120)."""

from __future__ import annotations

import io
import time

import pytest

from symkin.cli.progress import Progress, terminal_columns


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def _lines(columns: int, stage: str, monkeypatch) -> list[str]:
    monkeypatch.setenv("COLUMNS", str(columns))
    stream = Terminal()
    with Progress("model", stream=stream, delay=0.0) as progress:
        progress(stage)
        time.sleep(0.35)
    return [segment for segment in stream.getvalue().split("\r") if segment]


@pytest.mark.parametrize("columns", [40, 100, 200])
def test_the_line_is_as_wide_as_the_terminal_less_one_column(columns, monkeypatch):
    stage = "derive " + "x" * 300
    lines = _lines(columns, stage, monkeypatch)
    assert lines
    assert all(len(line) == columns - 1 for line in lines)     # never wraps, always clears the last
    assert lines[0].lstrip("|/-\\ ").startswith("[model] derive xxx")


def test_a_short_stage_on_a_wide_terminal_is_shown_whole(monkeypatch):
    stage = "stage " + "y" * 130                                          # longer than the old 120-column cut
    lines = _lines(200, stage, monkeypatch)
    assert stage in lines[0]


def test_the_width_comes_from_columns_then_the_terminal_then_80(monkeypatch):
    monkeypatch.setenv("COLUMNS", "132")
    assert terminal_columns(io.StringIO()) == 132
    monkeypatch.delenv("COLUMNS")
    assert terminal_columns(io.StringIO()) == 80                           # not a terminal: the fallback
