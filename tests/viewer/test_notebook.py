"""Notebooks (issue 19): ``symkin.load`` gives a model that Jupyter shows as the 3D viewer, and derived
symbolic quantities show as LaTeX where they are small."""

from __future__ import annotations

import html
import json
import re
import subprocess

import pytest
import sympy

from conftest import MODELS_DIR, SYMKIN_CLI
import symkin
from symkin.ir import spec
from symkin.runtime import LoadedModel
from symkin.viewer.notebook import NotebookModel


def test_a_loaded_model_shows_as_the_viewer_inline(generated_dir):
    model = symkin.load(generated_dir / "delta")
    assert isinstance(model, NotebookModel)
    assert isinstance(model, LoadedModel)
    assert isinstance(model.bind(a=0.11), NotebookModel)  # a bound design keeps its representation
    shown = model.bind(a=0.11)._repr_html_()
    # sandboxed: scripts run, in an opaque origin (no allow-same-origin: the page cannot reach the notebook)
    match = re.fullmatch(r'<iframe title="delta: symkin view" sandbox="allow-scripts" srcdoc="(.*)" style="[^"]*">'
                         r'</iframe>', shown, re.S)
    assert match, shown[:200]
    document = html.unescape(match.group(1))
    data = json.loads(re.search(r'id="symkin-data">(.*?)</script>', document, re.S).group(1))
    assert data["name"] == "delta"
    assert {p["name"]: p["value"] for p in data["parameters"]}["a"] == 0.11
    assert len(data["cloud"]["points"]) > 1000
    assert 'globalThis.symkin["delta"]' in document


def test_without_its_javascript_a_model_says_how_to_get_the_viewer(tmp_path):
    subprocess.run(SYMKIN_CLI + ["derive", str(MODELS_DIR / "planar_2r.yaml"), "--only", "fk,frames,jacobian",
                                 "--backend", "numpy", "-o", str(tmp_path), "-q"], check=True)
    shown = symkin.load(tmp_path / "planar_2r")._repr_html_()
    assert "needs its JavaScript" in shown
    assert "--backend numpy,js" in shown
    assert "<iframe" not in shown


def test_a_missing_attribute_names_the_generated_functions(generated_dir):
    with pytest.raises(AttributeError, match=r"planar_2r has no generated function or attribute 'ik' "
                                             r"\(generated: fk, frames,"):
        symkin.load(generated_dir / "planar_2r").ik  # noqa: B018


def test_small_derived_quantities_show_as_latex(derivations):
    fk = derivations["planar_2r"]["fk"]
    shown = fk._repr_latex_()
    assert shown.startswith(r"$\displaystyle \begin{aligned}\mathrm{base\_T\_tcp} &= ")
    assert shown.endswith("$")
    assert sympy.latex(fk.outputs[0].expr) in shown
    mass = derivations["planar_2r"]["mass_matrix"]._repr_latex_()
    assert r"w_{0} &= l_{1}^{2}" in mass
    assert r"\mathrm{M} &= " in mass
    assert "_w" not in mass
    assert fk.outputs[0]._repr_latex_() == shown


def test_large_derived_quantities_fall_back_to_text(derivations):
    ur_fk = derivations["ur10e"]["fk"]
    assert sympy.count_ops(ur_fk.outputs[0].expr) > spec.LATEX_MAX_OPS
    assert ur_fk._repr_latex_() is None
    assert derivations["ur10e"]["mass_matrix"]._repr_latex_() is None
