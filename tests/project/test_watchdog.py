"""Issue 59: SIGTERM ends a command within seconds, also while a long C call holds the interpreter lock
(symkin/cli/watchdog.py).  Reference: ``sum(range(10**11))``, a C loop that runs for minutes and never
returns to the bytecode loop where Python's signal handlers run; and ``time.sleep``, which does."""

from __future__ import annotations

import signal
import subprocess
import sys
import time

import pytest

SCRIPT = """
import signal, sys, time
from symkin.cli import _terminate
from symkin.cli.watchdog import terminate_within
signal.signal(signal.SIGTERM, _terminate)
with terminate_within(1.0):
    print("ready", flush=True)
    {work}
"""


@pytest.mark.parametrize("work, killed", [("sum(range(10**11))", True), ("time.sleep(120)", False)])
def test_sigterm_ends_the_command_within_the_grace_time(work, killed):
    process = subprocess.Popen([sys.executable, "-c", SCRIPT.format(work=work)], stdout=subprocess.PIPE, text=True)
    assert process.stdout.readline().strip() == "ready"
    time.sleep(0.2)  # inside the work
    start = time.monotonic()
    process.send_signal(signal.SIGTERM)
    code = process.wait(timeout=30)
    assert time.monotonic() - start < 10
    # a C loop: the watchdog kills it after the grace time; a sleep: the handler's SystemExit ends it at once
    assert code == (-signal.SIGKILL if killed else 128 + signal.SIGTERM)
