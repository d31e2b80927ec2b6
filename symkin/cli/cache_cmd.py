"""``symkin cache list|clear``: the derivations kept by ``symkin derive`` (:mod:`symkin.pipeline_cache`) and the
compiled C libraries kept by the C backend (:mod:`symkin.backends.c.cache`), and their eviction."""

from __future__ import annotations

import argparse
import time

from symkin.text_table import format_table

SECONDS_PER_DAY = 86400.0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("cache", help="list or clear the kept derivations and compiled C libraries",
                       description="symkin keeps two caches under one directory (SYMKIN_CACHE_DIR, else "
                                   "$XDG_CACHE_HOME/symkin or ~/.cache/symkin). Derivations: a derive (or an analysis "
                                   "command given a model file) keeps its generated files, keyed by the model file's "
                                   "content and name, the request and symkin's code and library versions, so that a "
                                   "repeated one copies them (--no-cache bypasses it). C libraries: the C backend "
                                   "compiles each generated model once, keyed by the source, the compiler and its "
                                   "flags. Changed models and flags add entries; 'list' shows them, 'clear' removes "
                                   "them (a library being built is left alone; the next use derives or builds again).")
    actions = p.add_subparsers(dest="action", metavar="ACTION", required=True)
    listing = actions.add_parser("list", help="the cached derivations and libraries: model, size, last use",
                                 description="List the cached derivations and libraries, least recently used first.")
    listing.set_defaults(run=run_list)
    clearing = actions.add_parser("clear", help="remove cached derivations and libraries",
                                  description="Remove cached derivations and libraries: all of them, or those of one "
                                              "model, or those not used for some days.")
    clearing.add_argument("--model", metavar="NAME", help="only this model's entries (e.g. delta)")
    clearing.add_argument("--older-than", type=_days, metavar="DAYS",
                          help="only entries last used more than DAYS days ago (e.g. 30, or 0.5)")
    clearing.add_argument("--kind", choices=("all", "derivations", "libraries"), default="all",
                          help="which cache (default: %(default)s)")
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
    from symkin import pipeline_cache
    from symkin.backends.c.build import cache_directory
    from symkin.backends.c.cache import cached_libraries

    now = time.time()
    derivations = pipeline_cache.cached_derivations()
    print(f"derivations: {pipeline_cache.directory(create=False)}")
    if derivations:
        print(format_table(["entry", "model", "size", "last used"],
                           [[d.path.name, d.model, _size(d.size), _age(now - d.last_used)] for d in derivations]))
    print(f"{_count(len(derivations), 'derivation', 'derivations')}, {_size(sum(d.size for d in derivations))}")
    libraries = cached_libraries()
    print(f"C build cache: {cache_directory()}")
    if libraries:
        print(format_table(["library", "model", "size", "last used"],
                           [[lib.path.name, lib.model, _size(lib.size), _age(now - lib.last_used)] for lib in libraries]))
    print(f"{_count(len(libraries), 'library', 'libraries')}, {_size(sum(lib.size for lib in libraries))}")
    return 0


def run_clear(args: argparse.Namespace) -> int:
    from symkin import pipeline_cache
    from symkin.backends.c.build import cache_directory
    from symkin.backends.c.cache import clear

    older = None if args.older_than is None else args.older_than * SECONDS_PER_DAY
    if args.kind in ("all", "derivations"):
        removed = pipeline_cache.clear(model=args.model, older_than=older)
        print(f"removed {_count(len(removed), 'derivation', 'derivations')} ({_size(sum(d.size for d in removed))}) "
              f"from {pipeline_cache.directory(create=False)}")
    if args.kind in ("all", "libraries"):
        eviction = clear(model=args.model, older_than=older)
        print(f"removed {_count(len(eviction.removed), 'library', 'libraries')} ({_size(eviction.freed)}) "
              f"from {cache_directory()}")
        for library in eviction.busy:
            print(f"  left {library.path.name}: a build holds its lock")
    return 0


def _count(count: int, one: str, many: str) -> str:
    return f"{count} {one if count == 1 else many}"
