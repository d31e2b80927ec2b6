"""Library entry points mirroring the CLI."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from symkin import pipeline
from symkin.model import Model, load_model


def derive(model: str | Path | Model, out_dir: str | Path = "generated", *,
           outputs: Sequence[str] | None = None, backends: Sequence[str] | None = None,
           fixed: Sequence[str] | None = None, float32: bool | None = None,
           combine: Sequence[str] | str | None = None) -> Path:
    """Derive a model and write its generated code, like ``symkin derive``.

    Args:
        model: a model file path or a loaded :class:`~symkin.model.Model`.
        out_dir: output directory; the code goes to ``out_dir/<model name>``.
        outputs: quantities to emit (default: the model's scene).
        backends: backends to run (default: the scene's, else numpy).
        fixed: parameters to fold (default: the scene's).
        float32: also emit single-precision C functions (default: the scene's).
        combine: outputs also fused into one function ``combined`` (default: the scene's, else all).

    Returns:
        The model's output directory, ready for :func:`symkin.load`.
    """
    if not isinstance(model, Model):
        model = load_model(model)
    request = pipeline.resolve_request(model, outputs, backends, fixed, float32, combine)
    pipeline.require_derivable(model, request)
    return pipeline.write(pipeline.generate(model, request), out_dir)
