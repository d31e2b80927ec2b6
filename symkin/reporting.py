"""How far long library work has come, for whoever shows it: a stage, and a count where the work is counted.

A loop deep in an analysis (a flood over a grid, a continuation, a simulation's time steps) calls
``report_progress("flooding the grid (cells reached)", done=k)`` or ``report_progress("simulating (periods)", done=k, total=n)``;
nothing happens unless a caller has installed a reporter with :func:`reporting_to` (the CLI's progress display
does, ``symkin.cli.progress.Progress``).  The reporter is held in a context variable, so library calls from
threads or from other callers that installed none report nothing, and no analysis passes a callback through the
functions between the command and its loop.
"""

from __future__ import annotations

import contextlib
import contextvars
from collections.abc import Callable, Iterator

#: A reporter: called with the stage and, where the work is counted, ``done`` and ``total`` (None if unknown).
Reporter = Callable[..., None]

_CURRENT: contextvars.ContextVar[Reporter | None] = contextvars.ContextVar("symkin_reporter", default=None)


def report_progress(stage: str, done: int | None = None, total: int | None = None) -> None:
    """Tell the installed reporter (if any) the stage, and how many of ``total`` items are ``done``."""
    reporter = _CURRENT.get()
    if reporter is not None:
        reporter(stage, done=done, total=total)


@contextlib.contextmanager
def reporting_to(reporter: Reporter) -> Iterator[None]:
    """Within the block, :func:`report_progress` calls ``reporter``; the one installed before is restored after."""
    token = _CURRENT.set(reporter)
    try:
        yield
    finally:
        _CURRENT.reset(token)
