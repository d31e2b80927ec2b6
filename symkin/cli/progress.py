"""A small progress display for the command line.

On a terminal, a status line shows the current stage and the elapsed time, refreshed by a
background thread, once the work has taken longer than ``delay`` seconds (quick commands
print nothing); it is one column narrower than the terminal, whatever its width.  When
stderr is not a terminal (CI logs, pipes), stages that take longer than ``delay`` are
reported as plain lines when they finish.
"""

from __future__ import annotations

import io
import os
import sys
import threading
import time
from types import TracebackType
from typing import TextIO


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


class Progress:
    """Use as a context manager; call it with a stage description."""

    def __init__(self, title: str, stream: TextIO | None = None, delay: float = 1.5, enabled: bool = True):
        self.title = title
        self.stream = stream or sys.stderr
        self.delay = delay
        self.enabled = enabled
        self.live = enabled and self.stream.isatty()
        self.start = time.perf_counter()
        self.stage = ""
        self.stage_start = self.start
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._shown = False
        self._width = 0

    def __enter__(self) -> Progress:
        if self.live:
            self._thread = threading.Thread(target=self._refresh, daemon=True)
            self._thread.start()
        return self

    def __call__(self, stage: str) -> None:
        with self._lock:
            self._finish_stage()
            self.stage = stage
            self.stage_start = time.perf_counter()

    def _finish_stage(self) -> None:
        elapsed = time.perf_counter() - self.stage_start
        if self.enabled and not self.live and self.stage and elapsed > self.delay:
            print(f"  [{self.title}] {self.stage}: {elapsed:.1f} s", file=self.stream, flush=True)

    def _refresh(self) -> None:
        spinner = "|/-\\"
        tick = 0
        while not self._stop.wait(0.1):
            elapsed = time.perf_counter() - self.start
            if elapsed < self.delay:
                continue
            with self._lock:
                line = f"{spinner[tick % 4]} [{self.title}] {self.stage} ({elapsed:5.1f} s)"
            # one column short of the terminal, so the line never wraps; padded, so it covers the last one
            self._width = max(1, terminal_columns(self.stream) - 1)
            self.stream.write("\r" + line[:self._width].ljust(self._width))
            self.stream.flush()
            self._shown = True
            tick += 1

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        with self._lock:
            self._finish_stage()
        if self._shown:
            self.stream.write("\r" + " " * self._width + "\r")
            self.stream.flush()
