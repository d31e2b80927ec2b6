"""Loaded models that Jupyter shows as the viewer of ``symkin view`` (``_repr_html_``).

``symkin.load`` returns a :class:`NotebookModel`: a :class:`~symkin.runtime.loader.LoadedModel`
whose rich representation is the page of :mod:`symkin.viewer.page`, inline in a sandboxed
``<iframe srcdoc>`` (the page keeps its own import map and scripts apart from the notebook's, and runs
in an opaque origin: scripts yes, the notebook's origin no).  Nothing is computed
until a notebook asks for the representation.
"""

from __future__ import annotations

import html
from pathlib import Path

from symkin.runtime.loader import LoadedModel
from symkin.runtime.loader import load as load_generated

#: Workspace points of the cloud shown inline (symkin view's default is larger).
NOTEBOOK_SAMPLES = 2048
#: Height of the inline viewer in CSS pixels.
HEIGHT = 600
#: What the inline page may do: run its own scripts, nothing more.  Without allow-same-origin its origin is
#: opaque, so a page made from a stranger's model file cannot reach the notebook (its cookies, its kernel).
SANDBOX = "allow-scripts"


class NotebookModel(LoadedModel):
    """A loaded model with the interactive 3D viewer as its notebook representation."""

    def _repr_html_(self) -> str:
        from symkin.viewer import page

        try:
            document, _ = page.page_of(self, NOTEBOOK_SAMPLES)
        except page.ViewUnavailable as err:
            return f"<p><b>{html.escape(self.name)}</b>: {html.escape(str(err))}</p>"
        return (f'<iframe title="{html.escape(self.name)}: symkin view" sandbox="{SANDBOX}" '
                f'srcdoc="{html.escape(document, quote=True)}" '
                f'style="width: 100%; height: {HEIGHT}px; border: 1px solid #ddd"></iframe>')


def load(path: str | Path, backend: str = "numpy") -> NotebookModel:
    """:func:`symkin.runtime.loader.load`, as a :class:`NotebookModel` (what ``symkin.load`` returns)."""
    return load_generated(path, backend, model_class=NotebookModel)
