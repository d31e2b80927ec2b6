"""The ``symkin`` command line: a thin layer over the library.

Exit codes: 0 success, 2 bad input (model file, arguments), 1 anything else.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import re
import signal
import sys
from collections.abc import Sequence

#: One BLAS thread per command unless the user says otherwise: symkin's linear algebra is many small matrices (stacks
#: of 3 x 3 to 100 x 100 solved one LAPACK call each, least squares of a few hundred columns), where OpenBLAS's
#: threads cost more than they win (``symkin identify --method consistent`` of the PHANToM: 10 s on one thread, 32 s
#: on two, on a 2-core machine); what runs in parallel is Dask's worker processes, which inherit this.  Set before
#: numpy is first imported (below), which reads it once.
BLAS_THREADS = {"OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
for _variable, _value in BLAS_THREADS.items():
    os.environ.setdefault(_variable, _value)

from symkin._version import __version__  # the imports from here on come after the BLAS threads are set
from symkin.cli import commands
from symkin.cli.watchdog import terminate_within
from symkin.errors import CacheTrustError, GeneratedCodeError, ModelDataError, ModelError, SymkinError


#: What a command line reads as a negative value, not an option: -60, -0.5, -1e-3 and -60deg
#: (argparse's own pattern stops at plain numbers, so ``--q0 0 -60deg`` was an unknown option).
NEGATIVE_VALUE = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?(deg)?$")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="symkin",
        description="Exact symbolic kinematics and dynamics of mechanisms declared in YAML, "
                    "emitted as fast numpy, C, CasADi and JavaScript code.",
        epilog="Run 'symkin COMMAND --help' for the options of a command.",
    )
    parser.add_argument("--version", action="version", version=f"symkin {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for register in commands.REGISTRY:
        register(sub)
    for command in sub.choices.values():
        # argparse's documented behaviour (a token that looks like a negative number is a value
        # when no option looks like one) keyed by its pattern attribute, widened to units.
        command._negative_number_matcher = NEGATIVE_VALUE
    return parser


def _terminate(signum: int, _frame: object) -> None:
    # Turn SIGTERM into an exception so that cleanup (temporary output directories) runs.
    raise SystemExit(128 + signum)


def _cache_choice(args: argparse.Namespace) -> contextlib.AbstractContextManager[None]:
    """--no-cache: the command derives model files afresh (the cache module is imported only then: start-up)."""
    if not getattr(args, "no_cache", False):
        return contextlib.nullcontext()
    from symkin import pipeline_cache

    return pipeline_cache.bypassed()


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    previous = signal.signal(signal.SIGTERM, _terminate)
    try:
        with terminate_within(), _cache_choice(args):
            code = int(args.run(args) or 0)
        sys.stdout.flush()  # here, where a closed pipe is caught below, not at the interpreter's exit
        return code
    except BrokenPipeError:
        # the reader of stdout went away ('symkin check models/*.yaml | head -1'): stop quietly, as a
        # command killed by SIGPIPE does; stdout goes to /dev/null so that Python's final flush cannot fail
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 128 + signal.SIGPIPE
    except ModelError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    except (GeneratedCodeError, CacheTrustError, ModelDataError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    except SymkinError as err:
        print(f"error: {err}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("interrupted; previous output left untouched", file=sys.stderr)
        return 130
    finally:
        signal.signal(signal.SIGTERM, previous)
