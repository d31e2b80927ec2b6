"""The ``symkin`` command line: a thin layer over the library.

Exit codes: 0 success, 2 bad input (model file, arguments), 1 anything else.
"""

from __future__ import annotations

import argparse
import signal
import sys
from collections.abc import Sequence

from symkin._version import __version__
from symkin.cli import commands
from symkin.errors import GeneratedCodeError, ModelError, SymkinError


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="symkin",
        description="Exact symbolic kinematics and dynamics of mechanisms declared in YAML, "
                    "emitted as fast numpy/C/CasADi code.",
        epilog="Run 'symkin COMMAND --help' for the options of a command.",
    )
    parser.add_argument("--version", action="version", version=f"symkin {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for register in commands.REGISTRY:
        register(sub)
    return parser


def _terminate(signum: int, _frame: object) -> None:
    # Turn SIGTERM into an exception so that cleanup (temporary output directories) runs.
    raise SystemExit(128 + signum)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    previous = signal.signal(signal.SIGTERM, _terminate)
    try:
        return int(args.run(args) or 0)
    except ModelError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    except GeneratedCodeError as err:
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
