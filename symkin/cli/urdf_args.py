"""Options that choose what of a URDF becomes the model (``symkin check`` and ``symkin derive``).

The model is the whole tree below the root link (or ``--base``), its TCP on ``--tip`` (``--frame``); with
``--chain`` it is the chain to the tip alone (with ``--branch`` the paths to the tip and the branches): every
joint off it is locked (``--lock JOINT=VALUE``, default 0) and what it carries is lumped into the chain link it
hangs on (:mod:`symkin.model.urdf_source`); ``--snap-angles`` reads an angle that is a multiple of
pi/2, pi/4, pi/3 or pi/6 rounded to the digits written (1.5708, 3.14159) as that multiple.  The
options apply to URDF and xacro files only;
``--xacro-arg NAME:=VALUE`` and ``--xacro-package NAME=DIR`` to xacro files
(:mod:`symkin.model.xacro_source`).
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from typing import Any

from symkin.cli.analysis_args import parse_value
from symkin.errors import ModelError, Problem


#: The options of robot files (argparse destinations).
ROBOT_FILE_OPTIONS = ("tip", "chain", "base", "branch", "lock", "snap_angles", "xacro_arg", "xacro_package",
                      "allow_read")


def add_urdf_arguments(p: argparse.ArgumentParser) -> None:
    group = p.add_argument_group("URDF, xacro and MJCF files (MJCF: bodies are links)")
    group.add_argument("--tip", "--frame", dest="tip", metavar="LINK",
                       help="the link that carries the TCP, the task frame of fk, the Jacobians and the "
                            "operational-space quantities; the model stays the whole tree (default: the leaf "
                            "behind the most moving joints)")
    group.add_argument("--chain", action="store_true",
                       help="a smaller model: the chain from the base to --tip alone, every joint off it locked "
                            "(--lock) and what it carries lumped into the chain link it hangs on (default: the "
                            "whole tree)")
    group.add_argument("--base", metavar="LINK", help="the link the chain starts from (default: the root link)")
    group.add_argument("--branch", action="append", default=[], metavar="LINK",
                       help="a smaller model: the tree of the paths to --tip (which carries the TCP) and to each "
                            "--branch link, the rest locked and lumped as for --chain (repeatable)")
    group.add_argument("--lock", action="append", default=[], metavar="JOINT=VALUE",
                       help="with --chain or --branch: the value of a joint off the model, in rad or m, or "
                            "degrees with 'deg' (repeatable; default 0, a mimic joint follows its leader)")
    group.add_argument("--snap-angles", action="store_true",
                       help="read an angle that is a multiple of pi/2, pi/4, pi/3 or pi/6 rounded to the digits "
                            "written (1.57079632679, 1.5708, 3.14159) as that multiple, noted; crosscheck feeds its "
                            "reference the same angles (default: as written)")
    group.add_argument("--xacro-arg", action="append", default=[], metavar="NAME:=VALUE",
                       help="the value of a <xacro:arg> of a xacro file (repeatable; default: the file's default)")
    group.add_argument("--xacro-package", action="append", default=[], metavar="NAME=DIR",
                       help="the directory of the ROS package NAME for $(find NAME) (repeatable; default: the "
                            "nearest directory with a package.xml naming it, around the file)")
    group.add_argument("--allow-read", action="append", default=[], metavar="DIR",
                       help="a folder a xacro or MJCF file may also read from (repeatable; default: only its own "
                            "folder tree, the ROS package holding it and the packages it finds)")
    p.add_argument("--allow-nonphysical", action="store_true",
                   help="accept inertia tensors that violate the triangle inequality, with a note, as simulators "
                        "do (default: refuse them; the model key 'allow_nonphysical: true' does the same)")


def urdf_options(args: argparse.Namespace, path: str) -> dict[str, Any]:
    """Keyword arguments of :func:`symkin.model.load_model` for the model file ``path``.

    Raises:
        ModelError: robot-file (or xacro) options given with no such file among the models, or a malformed
            --lock.
    """
    from symkin.model.source_kind import MJCF, URDF, XACRO, source_kind  # the model package imports sympy

    # (options, the file kinds they apply to, those kinds in words, a suffix of such a file)
    option_kinds = ((("--tip", "--chain", "--base", "--lock", "--snap-angles", "--branch"), {URDF, XACRO, MJCF},
                     "robot files (URDF, xacro, MJCF)", ".urdf"),
                    (("--xacro-arg", "--xacro-package"), {XACRO}, "xacro files", ".xacro"),
                    (("--allow-read",), {XACRO, MJCF}, "xacro and MJCF files", ".xacro"))
    kinds = {source_kind(model) for model in getattr(args, "models", None) or [path]}
    for names, accepting, what, suffix in option_kinds:
        given = [option for option in names if getattr(args, option[2:].replace("-", "_"))]
        if given and not kinds & accepting:
            raise ModelError([Problem("<command line>", None, None, given[0], f"{given[0]} applies to {what} only",
                                      f"drop {given[0]}, or pass a {suffix} file")])
    kind = source_kind(path)
    if kind not in (URDF, XACRO, MJCF):
        return {"allow_nonphysical": args.allow_nonphysical}
    locks = {}
    for item in args.lock:
        name, _, value = item.partition("=")
        try:
            locks[name.strip()] = parse_value(value)
        except ValueError:
            raise ModelError([Problem("<command line>", None, None, "--lock", f"--lock '{item}' is not JOINT=VALUE",
                                      "write e.g. --lock finger_joint1=0.02 or --lock head_pan=30deg")]) from None
    options = {"tip": args.tip, "base": args.base, "locks": locks, "snap_angles": args.snap_angles,
               "allow_nonphysical": args.allow_nonphysical, "branches": tuple(args.branch),
               "chain": args.chain}
    if kind in (XACRO, MJCF):
        options["allow_read"] = tuple(args.allow_read)
    if kind == XACRO:
        options["xacro_args"] = _pairs(args.xacro_arg, ":=", "--xacro-arg", "robot_name:=arm")
        options["xacro_packages"] = _pairs(args.xacro_package, "=", "--xacro-package", "kuka_kr6_support=./kuka_kr6")
    return options


def _pairs(items: list[str], separator: str, option: str, example: str) -> dict[str, str]:
    """{NAME: VALUE} of repeated ``NAME<separator>VALUE`` options."""
    pairs = {}
    for item in items:
        name, sep, value = item.partition(separator)
        if not sep or not name.strip():
            raise ModelError([Problem("<command line>", None, None, option, f"{option} '{item}' is not "
                                      f"NAME{separator}VALUE", f"write e.g. {option} {example}")])
        pairs[name.strip()] = value
    return pairs


def print_notes(source: str, notes: Sequence[str]) -> None:
    """Print what the reading of the model file ``source`` decided (Model.notes), one line each, as plain text."""
    from symkin.backends.comments import plain

    for note in notes:
        print(f"  note: {plain(source)}, {plain(note)}")
