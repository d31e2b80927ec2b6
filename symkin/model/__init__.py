"""Mechanism models: read a YAML model file into a frozen, validated :class:`Model`."""

from __future__ import annotations

from pathlib import Path

from symkin.model.build import build_model
from symkin.model.schema import Body, Friction, Joint, JointType, Model, Parameter, Rotation, Scene, Translation
from symkin.model.yaml_source import parse_document, read_document

__all__ = ["Body", "Friction", "Joint", "JointType", "Model", "Parameter", "Rotation", "Scene", "Translation",
           "load_model", "model_from_text"]


def load_model(path: str | Path) -> Model:
    """Read, validate and build the model in the YAML file ``path``.

    Raises:
        symkin.errors.ModelError: with every problem found, each located in the file.
    """
    return build_model(read_document(path), Path(path).stem)


def model_from_text(text: str, name: str = "model", file: str = "<string>") -> Model:
    """Build a model from YAML text (for tests and notebooks); ``name`` is the default model name."""
    return build_model(parse_document(text, file), name)
