"""Mechanism models: read a YAML model file (or a URDF, xacro or MJCF file, told by its content) into a
frozen, validated :class:`Model`."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from symkin.errors import ModelError, Problem
from symkin.model.build import build_model
from symkin.model.schema import Body, Friction, Joint, JointType, Model, Parameter, Rotation, Scene, Translation
from symkin.model.source_kind import MJCF, URDF, XACRO, source_kind
from symkin.model.mjcf_source import read_mjcf_document
from symkin.model.urdf_source import read_urdf_document
from symkin.model.xacro_source import read_xacro_document
from symkin.model.yaml_source import Document, parse_document, read_document

__all__ = ["Body", "Friction", "Joint", "JointType", "Model", "Parameter", "Rotation", "Scene", "Translation",
           "load_model", "model_from_text", "read_model_document"]


def load_model(path: str | Path, tip: str | None = None, *, allow_nonphysical: bool = False,
               **reading: Any) -> Model:
    """Read, validate and build the model in the file ``path``: YAML, URDF, xacro or MJCF, told by its
    content (root element ``<robot>``, with ``<xacro:...>`` elements or a ``.xacro`` name for xacro;
    ``<mujoco>`` for MJCF, read through MuJoCo's compiler).

    Args:
        path: the model file.
        tip, reading: how a robot file is read (:func:`read_model_document`).
        allow_nonphysical: accept inertia tensors that violate the triangle inequality (or have a
            negative principal moment) with a note in ``Model.notes`` instead of refusing them.

    Raises:
        symkin.errors.ModelError: with every problem found, each located in the file.
    """
    name = _stem(path) if source_kind(path) in (MJCF, XACRO) else Path(path).stem
    return build_model(read_model_document(path, tip, **reading), name, allow_nonphysical)


def read_model_document(path: str | Path, tip: str | None = None, *, base: str | None = None,
                        locks: Mapping[str, float] | None = None, snap_angles: bool = False,
                        xacro_args: Mapping[str, str] | None = None,
                        xacro_packages: Mapping[str, str | Path] | None = None, branches: Sequence[str] = (),
                        allow_read: Sequence[str | Path] = (), chain: bool = False) -> Document:
    """The model document of the file ``path`` (what :func:`load_model` builds the model from; what
    ``symkin identify`` rewrites with the identified values), read by its kind with the robot-file options.

    Args:
        path: the model file.
        tip: URDF, xacro and MJCF (a body) only: the link that carries the TCP, the task frame; it does not cut
            the tree (default: the leaf behind the most moving joints).
        chain: URDF, xacro and MJCF only: the model is the chain from the base to ``tip`` alone, every joint off
            it locked and what it carries lumped (``--chain``; default: the whole tree).
        base: URDF only: the link the chain starts from (default: the root link).
        locks: URDF only: {joint: value} of joints off the chain (with ``chain`` or ``branches``; default 0; see
            :mod:`symkin.model.urdf_source`).
        snap_angles: URDF only: read an angle that is a multiple of pi/2, pi/4, pi/3 or pi/6 rounded to the digits
            written as that multiple (:func:`symkin.model.urdf_source.snap_angle`).
        xacro_args: xacro only: values of its ``<xacro:arg>`` (``--xacro-arg NAME:=VALUE``).
        xacro_packages: xacro only: {package: directory} for ``$(find package)`` (``--xacro-package``).
        branches: URDF, xacro and MJCF only: more links whose joints from the base stay moving (the model is
            the tree of the paths to the tip and to them; ``--branch LINK``).
        allow_read: xacro and MJCF only: more folders the file may read from (``--allow-read DIR``; by default
            its own folder tree and the ROS packages it names, see :mod:`symkin.model.confined_read`).

    Raises:
        symkin.errors.ModelError: with every problem found, each located in the file.
    """
    robot: dict[str, Any] = {"tip": tip, "base": base, "locks": locks, "snap_angles": snap_angles,
                             "branches": branches, "chain": chain}
    kind = source_kind(path)
    if kind == MJCF:
        if xacro_args or xacro_packages:
            raise ModelError([Problem(str(path), None, None, "", "xacro arguments and packages apply to xacro "
                                      "files only", "drop them, or pass a .xacro file")])
        return read_mjcf_document(path, allow_read=allow_read, **robot)[0]
    if kind == XACRO:
        return read_xacro_document(path, xacro_args, xacro_packages, allow_read, **robot)[0]
    if allow_read:
        raise ModelError([Problem(str(path), None, None, "", "--allow-read applies to xacro and MJCF files only (a "
                                  "URDF or YAML file reads no other file)", "drop it")])
    if xacro_args or xacro_packages:
        raise ModelError([Problem(str(path), None, None, "", "xacro arguments and packages apply to xacro files only",
                                  "drop them, or pass a .xacro file")])
    if kind == URDF:
        return read_urdf_document(path, **robot)
    given = [name for name, value in robot.items() if value]
    if given:
        raise ModelError([Problem(str(path), None, None, "", f"{given[0]} applies to robot files (URDF, xacro, "
                                  "MJCF) only", f"drop {given[0]}, or pass a .urdf file")])
    return read_document(path)


def _stem(path: str | Path) -> str:
    """The model's default name from a robot file's name: ``arm.urdf.xacro`` -> ``arm``."""
    name = Path(path).name
    for suffix in (".xacro", ".urdf", ".xml"):
        name = name[:-len(suffix)] if name.lower().endswith(suffix) and len(name) > len(suffix) else name
    return name


def model_from_text(text: str, name: str = "model", file: str = "<string>") -> Model:
    """Build a model from YAML text (for tests and notebooks); ``name`` is the default model name."""
    return build_model(parse_document(text, file), name)
