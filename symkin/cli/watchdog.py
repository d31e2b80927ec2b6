"""SIGTERM ends a command within :data:`GRACE` seconds, even while a long C call holds the interpreter (issue 59).

The command line turns SIGTERM into ``SystemExit`` (:func:`symkin.cli._terminate`) so that temporary folders
are removed; but Python runs a signal handler only between bytecodes, and a C call that runs for minutes
(a symbolic simplification in SymEngine, a solver, ``sum`` over a huge range) defers it as long.  A thread
cannot help: it needs the interpreter lock that the C call holds.  So :func:`terminate_within` hands the
signal to a small watchdog *process*: CPython's own C-level signal handler writes the signal number to a
pipe as the signal arrives (:func:`signal.set_wakeup_fd`, async-signal-safe, no lock needed), the watchdog
reads it, and if the command has not ended (the pipe's end of file) after :data:`GRACE` seconds, kills it
with SIGKILL.  Outputs stay whole either way: they are replaced by renames with signals held
(:mod:`symkin.atomic`), so a kill leaves the previous output or the complete new one.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import threading
from collections.abc import Iterator

#: Seconds a terminated command has to end by itself (clean up) before it is killed.
GRACE = 5.0

_WATCHDOG = r"""
import os, select, signal, sys, time
parent, grace = int(sys.argv[1]), float(sys.argv[2])
while True:
    data = os.read(0, 256)
    if not data:
        sys.exit(0)                      # the command ended: the pipe's last writer closed it
    if signal.SIGTERM in data:
        deadline = time.monotonic() + grace
        while time.monotonic() < deadline:
            ready, _, _ = select.select([0], [], [], max(deadline - time.monotonic(), 0))
            if ready and not os.read(0, 256):
                sys.exit(0)              # it ended within the grace time
        try:
            os.kill(parent, signal.SIGKILL)
        except ProcessLookupError:
            pass
        sys.exit(0)
"""


@contextlib.contextmanager
def terminate_within(grace: float = GRACE) -> Iterator[None]:
    """While the block runs, a SIGTERM ends the process within ``grace`` seconds (see the module docstring).
    A no-op outside the main thread, off POSIX, or where no watchdog can be started."""
    if os.name != "posix" or threading.current_thread() is not threading.main_thread():
        yield
        return
    read, write = os.pipe()
    os.set_blocking(write, False)
    try:
        watchdog = subprocess.Popen([sys.executable, "-I", "-S", "-c", _WATCHDOG, str(os.getpid()), str(grace)],
                                    stdin=read, close_fds=True, start_new_session=True)
    except OSError:
        os.close(read)
        os.close(write)
        yield
        return
    os.close(read)
    previous = signal.set_wakeup_fd(write, warn_on_full_buffer=False)
    try:
        yield
    finally:
        signal.set_wakeup_fd(previous)
        os.close(write)  # end of file: the watchdog exits
        try:
            watchdog.wait(timeout=grace + 5)
        except subprocess.TimeoutExpired:
            watchdog.kill()
