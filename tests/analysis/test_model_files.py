"""A model file derived on the fly (symkin.analysis.model_files): a second command on the same mechanism in one
process goes on with the first one's derivation graph (symkin identify after symkin excite: the base parameters are
not derived again); a changed mechanism starts a new graph."""

from __future__ import annotations

import pytest

from conftest import MODELS_DIR
from symkin.analysis import model_files


@pytest.fixture
def no_cache(monkeypatch):
    """The derivation cache off (--no-cache), so that each call derives: the memo of the graph is what is checked."""
    from symkin import pipeline_cache

    monkeypatch.setattr(model_files, "_LAST_DERIVATION", {})
    with pipeline_cache.bypassed():
        yield


def test_a_second_derive_of_the_same_mechanism_goes_on_with_its_graph(tmp_path, no_cache):
    path = tmp_path / "planar_2r.yaml"
    path.write_text((MODELS_DIR / "planar_2r.yaml").read_text())
    first = model_files.generated_model(str(path), "numpy", ["fk", "jacobian"])
    (graph,) = [derivation for _, derivation in model_files._LAST_DERIVATION.values()]
    assert "jacobian" in graph.computed
    second = model_files.generated_model(str(path), "numpy", ["mass_matrix"])
    assert [d for _, d in model_files._LAST_DERIVATION.values()] == [graph]    # the same graph, gone on with
    assert "mass_matrix" in graph.computed
    assert set(first.info.functions) == {"fk", "jacobian"}
    assert set(second.info.functions) == {"mass_matrix"}
    path.write_text(path.read_text().replace("value: 0.1", "value: 0.15", 1))   # another mechanism
    model_files.generated_model(str(path), "numpy", ["fk"])
    (other,) = [derivation for _, derivation in model_files._LAST_DERIVATION.values()]
    assert other is not graph
    assert "mass_matrix" not in other.computed
