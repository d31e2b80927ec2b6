"""Mechanism models: read a YAML model file (or a URDF) into a frozen, validated :class:`Model`."""

from __future__ import annotations

from pathlib import Path

from symkin.errors import ModelError, Problem
from symkin.model.build import build_model
from symkin.model.schema import Body, Friction, Joint, JointType, Model, Parameter, Rotation, Scene, Translation
from symkin.model.urdf_source import read_urdf_document
from symkin.model.yaml_source import parse_document, read_document

__all__ = ["Body", "Friction", "Joint", "JointType", "Model", "Parameter", "Rotation", "Scene", "Translation",
           "load_model", "model_from_text"]


def load_model(path: str | Path, tip: str | None = None) -> Model:
    """Read, validate and build the model in the file ``path``: YAML, or URDF (``.urdf``).

    Args:
        path: the model file.
        tip: URDF only: the link that ends the chain (default: the single leaf link).

    Raises:
        symkin.errors.ModelError: with every problem found, each located in the file.
    """
    if Path(path).suffix.lower() == ".urdf":
        return build_model(read_urdf_document(path, tip), Path(path).stem)
    if tip is not None:
        raise ModelError([Problem(str(path), None, None, "", "a tip link applies to URDF files only",
                                  "drop the tip, or pass a .urdf file")])
    return build_model(read_document(path), Path(path).stem)


def model_from_text(text: str, name: str = "model", file: str = "<string>") -> Model:
    """Build a model from YAML text (for tests and notebooks); ``name`` is the default model name."""
    return build_model(parse_document(text, file), name)
