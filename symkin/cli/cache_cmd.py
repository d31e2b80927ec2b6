"""``symkin cache list|clear``: the compiled C libraries kept by the C backend, and their eviction."""

from __future__ import annotations

import argparse
import time

from symkin.text_table import format_table

SECONDS_PER_DAY = 86400.0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("cache", help="list or clear the compiled C libraries",
                       description="The C backend compiles each generated model once and keeps the library in a "
                                   "cache (SYMKIN_CACHE_DIR, else $XDG_CACHE_HOME/symkin or ~/.cache/symkin), keyed "
                                   "by the source, the compiler and its flags; regenerated models and changed flags "
                                   "add libraries. 'list' shows them, 'clear' removes them (a library being built "
                                   "is left alone; the next load rebuilds a removed one).")
    actions = p.add_subparsers(dest="action", metavar="ACTION", required=True)
    listing = actions.add_parser("list", help="the cached libraries: model, size, last use",
                                 description="List the cached libraries, least recently used first.")
    listing.set_defaults(run=run_list)
    clearing = actions.add_parser("clear", help="remove cached libraries",
                                  description="Remove the cached libraries: all of them, or those of one model, or "
                                              "those not used for some days.")
    clearing.add_argument("--model", metavar="NAME", help="only this model's libraries (e.g. delta)")
    clearing.add_argument("--older-than", type=_days, metavar="DAYS",
                          help="only libraries last used more than DAYS days ago (e.g. 30, or 0.5)")
    clearing.set_defaults(run=run_clear)


def _days(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a number of days") from None
    if not value >= 0:
        raise argparse.ArgumentTypeError(f"'{text}': the age must be zero or more days")
    return value


def _size(size: int) -> str:
    return f"{size / 1e6:.2f} MB" if size >= 1e5 else f"{size / 1e3:.1f} kB"


def _age(seconds: float) -> str:
    if seconds < 3600:
        return f"{seconds / 60:.0f} min ago"
    if seconds < SECONDS_PER_DAY:
        return f"{seconds / 3600:.1f} h ago"
    return f"{seconds / SECONDS_PER_DAY:.1f} days ago"


def run_list(args: argparse.Namespace) -> int:
    from symkin.backends.c.build import cache_directory
    from symkin.backends.c.cache import cached_libraries

    libraries = cached_libraries()
    now = time.time()
    print(f"C build cache: {cache_directory()}")
    if libraries:
        print(format_table(["library", "model", "size", "last used"],
                           [[lib.path.name, lib.model, _size(lib.size), _age(now - lib.last_used)] for lib in libraries]))
    print(f"{len(libraries)} librar{'y' if len(libraries) == 1 else 'ies'}, {_size(sum(lib.size for lib in libraries))}")
    return 0


def run_clear(args: argparse.Namespace) -> int:
    from symkin.backends.c.build import cache_directory
    from symkin.backends.c.cache import clear

    older = None if args.older_than is None else args.older_than * SECONDS_PER_DAY
    eviction = clear(model=args.model, older_than=older)
    print(f"removed {len(eviction.removed)} librar{'y' if len(eviction.removed) == 1 else 'ies'} "
          f"({_size(eviction.freed)}) from {cache_directory()}")
    for library in eviction.busy:
        print(f"  left {library.path.name}: a build holds its lock")
    return 0
