"""What a long command is doing: its stage, a count where the work is counted, and an estimate of the time left.

On a terminal, once the work has taken longer than ``delay`` seconds (quick commands print nothing), a status line
drawn by rich (a spinner, ``[model] stage``, ``k/N`` and about how long is left, the elapsed time) is kept up to date
and cleared at the end; it never wraps, whatever the terminal's width.  When stderr is not a terminal (CI logs,
pipes), a stage that has run ``delay`` seconds is announced by a plain line, followed every ``log_interval`` seconds
by its count and estimate, and closed by a line with its time.

A stage is counted when the caller says how far it is: ``progress("deriving fk", done=3, total=12)``.  The estimate
is the time per item so far times the items left, from the first report of that total; a count without a total
(cells a flood has reached) is shown as it is.  While the display is open it is the installed reporter of
:mod:`symkin.reporting`, so the loops of the library (floods, continuations, simulations) report into it.
"""

from __future__ import annotations

import contextlib
import io
import os
import sys
import threading
import time
from types import TracebackType
from typing import Any, TextIO

from symkin import reporting

#: Seconds between the lines a long stage writes into a log.
LOG_INTERVAL = 10.0


def terminal_columns(stream: TextIO) -> int:
    """The width of the terminal ``stream`` writes to: $COLUMNS if set, else the terminal's own
    (asked each time: a window may be resized), else 80."""
    explicit = os.environ.get("COLUMNS", "")
    if explicit.isdigit() and int(explicit) > 0:
        return int(explicit)
    try:
        return os.get_terminal_size(stream.fileno()).columns
    except (AttributeError, OSError, ValueError, io.UnsupportedOperation):
        return 80


def _duration(seconds: float) -> str:
    return f"{seconds:.0f} s" if seconds < 90 else f"{seconds / 60:.1f} min"


class Progress:
    """Use as a context manager; call it with a stage description (and ``done``, ``total`` where counted)."""

    def __init__(self, title: str, stream: TextIO | None = None, delay: float = 1.5, enabled: bool = True,
                 log_interval: float = LOG_INTERVAL):
        self.title = title
        self.stream = stream or sys.stderr
        self.delay = delay
        self.enabled = enabled
        self.log_interval = log_interval
        self.live = enabled and self.stream.isatty()
        self.start = time.perf_counter()
        self.stage = ""
        self.stage_start = self.start
        self.done: int | None = None
        self.total: int | None = None
        self._count_start = self.start
        self._count_first = 0
        self._logged_at: float | None = None
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._display: Any = None  # the rich display (rich.progress.Progress), started once the work outlasts ``delay``
        self._task: Any = None
        self._reporting = contextlib.ExitStack()

    def __enter__(self) -> Progress:
        self._reporting.enter_context(reporting.reporting_to(self))
        if self.enabled:
            self._thread = threading.Thread(target=self._watch, daemon=True)
            self._thread.start()
        return self

    def __call__(self, stage: str, done: int | None = None, total: int | None = None) -> None:
        with self._lock:
            if stage != self.stage:
                self._finish_stage()
                self.stage, self.stage_start, self._logged_at = stage, time.perf_counter(), None
            if total != self.total or done is None:
                self._count_start, self._count_first = time.perf_counter(), done or 0
            self.done, self.total = done, total

    def status(self) -> str:
        """'[model] stage: 3/12, about 20 s left' (the count and estimate where the stage is counted)."""
        text = f"[{self.title}] {self.stage}"
        if self.done is None:
            return text
        if self.total is None:
            return f"{text}: {self.done}"
        text += f": {self.done}/{self.total}"
        left = self.remaining()
        return text if left is None else f"{text}, about {_duration(left)} left"

    def remaining(self) -> float | None:
        """Seconds left at the pace since the count began (None before the first item is done)."""
        if self.total is None or self.done is None:
            return None
        finished = self.done - self._count_first
        if finished <= 0:
            return None
        return (time.perf_counter() - self._count_start) / finished * max(self.total - self.done, 0)

    def _finish_stage(self) -> None:
        elapsed = time.perf_counter() - self.stage_start
        if self.enabled and not self.live and self.stage and elapsed > self.delay:
            print(f"  [{self.title}] {self.stage}: {elapsed:.1f} s", file=self.stream, flush=True)

    def _watch(self) -> None:
        while not self._stop.wait(0.1):
            now = time.perf_counter()
            with self._lock:
                if self.live:
                    if now - self.start >= self.delay:
                        self._draw()
                elif self.stage and now - self.stage_start >= self.delay and (
                        self._logged_at is None or now - self._logged_at >= self.log_interval):
                    print(f"  {self.status()}{'' if self._logged_at is not None else ' ...'}", file=self.stream,
                          flush=True)
                    self._logged_at = now

    def _draw(self) -> None:
        """Start or refresh the rich status line (under the lock)."""
        from rich.console import Console
        from rich.progress import Progress as Display
        from rich.progress import SpinnerColumn, TextColumn, TimeElapsedColumn
        from rich.table import Column

        if self._display is None:
            console = Console(file=self.stream, force_terminal=True, width=max(1, terminal_columns(self.stream) - 1),
                              highlight=False, markup=False)
            line = Column(no_wrap=True, overflow="ellipsis", ratio=1)  # one line, cut to the terminal
            self._display = Display(SpinnerColumn(), TextColumn("{task.description}", markup=False, table_column=line),
                                    TimeElapsedColumn(), console=console, transient=True, expand=True,
                                    refresh_per_second=10)
            self._display.start()
            self._task = self._display.add_task(self.status(), total=None)
        self._display.console.width = max(1, terminal_columns(self.stream) - 1)  # a window may be resized
        self._display.update(self._task, description=self.status())

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self._reporting.close()
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        with self._lock:
            self._finish_stage()
            if self._display is not None:
                self._display.stop()
