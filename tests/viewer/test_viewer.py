"""``symkin view`` (issue 19): one self-contained page per model, from generated directories, model files
and stock URDFs; bad input exits 2 and writes nothing.  The page in a real browser: test_viewer_browser.py."""

from __future__ import annotations

import hashlib
import json
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

from conftest import EXAMPLE_MODELS, MODELS_DIR, SYMKIN_CLI
from symkin import load
from symkin.analysis import global_indices
from symkin import mechanism
from symkin.mechanism import reach
from symkin.viewer import page
from tolerances import KINEMATICS
from sample_models import ROBOTS_DIR

VENDOR = Path(page.__file__).parent / "vendor"


def view(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(SYMKIN_CLI + ["view", *args], capture_output=True, text=True, cwd=cwd)


def page_parts(html: str) -> tuple[dict, dict]:
    """(the page's data, its import map)."""
    data = re.search(r'<script type="application/json" id="symkin-data">(.*?)</script>', html, re.S).group(1)
    importmap = re.search(r'<script type="importmap">(.*?)</script>', html, re.S).group(1)
    return json.loads(data), json.loads(importmap)


def assert_self_contained(html: str) -> None:
    """Nothing is fetched: no src or href attributes, every module a data: URL."""
    assert not re.search(r"<(script|link|img|iframe)[^>]*\s(src|href)=", html, re.I)
    _, importmap = page_parts(html)
    assert set(importmap["imports"]) == {"three", "three/addons/controls/OrbitControls.js"}
    assert all(url.startswith("data:text/javascript;base64,") for url in importmap["imports"].values())


@pytest.mark.parametrize("name", EXAMPLE_MODELS)
def test_every_example_model_gets_a_self_contained_page(name, generated_dir):
    """In process (the command is run by the tests below): the page of every example model."""
    model = load(generated_dir / name)
    html, _ = page.page_of(model, 1024)
    assert_self_contained(html)
    data, _ = page_parts(html)
    assert data["name"] == name
    assert data["kind"] == ("parallel" if model.info.is_parallel else "serial")
    assert f'globalThis.symkin[{json.dumps(name)}]' in html  # the generated module, inlined
    # the sliders' heading says how the page solves (issue 60: not 'closed-form' over a Gauss-Newton page)
    assert ("<h2>Platform (closed-form inverse kinematics)</h2>" in html) == model.info.is_parallel
    cloud = data["cloud"]
    assert [c["name"] for c in data["coordinates"]] == [c.name for c in model.info.coordinates]
    if mechanism.kind_of(model) is mechanism.MechanismKind.PARALLEL_ORIENTATION:  # a spherical platform: no cloud
        assert cloud["points"] == []
        assert "set of orientations" in page.workspace_cloud(model, 1024).note
        return
    assert len(cloud["points"]) >= 512
    assert len(cloud["points"]) == len(cloud["inverse_kappa"])
    assert all(0 <= v <= 1 for v in cloud["inverse_kappa"])
    assert cloud["colour_max"] == max(cloud["inverse_kappa"])


def test_the_cloud_is_rated_as_the_analyses_rate_it(generated_dir):
    """Points are the workspace sample's TCP positions; 1/kappa is local_index's (homogenized for the UR10e)."""
    model = load(generated_dir / "ur10e")
    cloud = page.workspace_cloud(model, 256)
    assert cloud.length == pytest.approx(reach.characteristic_length_of(model))
    np.testing.assert_array_equal(cloud.inverse_kappa, global_indices.local_index(model, cloud.q, length=cloud.length))
    extent = 2.0  # m: the UR10e's TCP stays within 1.4 m of the base
    np.testing.assert_allclose(cloud.points, np.stack([model.fk(q)[:3, 3] for q in cloud.q]), rtol=0,
                               atol=KINEMATICS * extent)


@pytest.mark.parametrize("source", [MODELS_DIR / "delta.yaml", MODELS_DIR / "ur10e.urdf",
                                    ROBOTS_DIR / "so_arm_description/urdf/so100.urdf"], ids=lambda p: p.name)
def test_model_files_and_stock_urdfs_are_derived_on_the_fly(source, tmp_path):
    run = view(str(source), "--workspace", "512", cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    (written,) = (tmp_path / "out" / "view").glob("*-view.html")   # under out/, not beside the user's files
    html = written.read_text()
    assert_self_contained(html)
    data, _ = page_parts(html)
    assert written.name == f"{data['name']}-view.html"
    assert data["cloud"]["points"]


def test_a_design_is_shown_and_sampled_with_its_parameters(generated_dir, tmp_path):
    out = tmp_path / "long.html"
    assert view(str(generated_dir / "planar_2r"), "-o", str(out), "--design", "l1=0.2", "--workspace", "400").returncode == 0
    data, _ = page_parts(out.read_text())
    assert {p["name"]: p["value"] for p in data["parameters"]} == {"l1": 0.2, "l2": 0.1}
    farthest = np.linalg.norm(np.array(data["cloud"]["points"]), axis=1).max()
    assert 0.29 < farthest <= 0.3 + 1e-6  # l1 + l2 with the longer first link


def test_bad_input_exits_2_and_writes_nothing(generated_dir, tmp_path):
    out = tmp_path / "page.html"
    unknown = view(str(generated_dir / "planar_2r"), "-o", str(out), "--design", "l9=1")
    assert unknown.returncode == 2
    assert "l9" in unknown.stderr
    assert not out.exists()
    numpy_only = tmp_path / "numpy-only"
    subprocess.run(SYMKIN_CLI + ["derive", str(MODELS_DIR / "planar_2r.yaml"), "--backend", "numpy", "-o",
                                 str(numpy_only), "-q"], check=True)
    missing = view(str(numpy_only / "planar_2r"), "-o", str(out))
    assert missing.returncode == 2
    assert "--backend numpy,js" in missing.stderr
    assert not out.exists()
    assert view(str(tmp_path / "nowhere.yaml"), "-o", str(out)).returncode == 2
    assert not out.exists()


def test_the_vendored_files_are_the_ones_vendor_md_names():
    table = dict(re.findall(r"\| `([^`]+)` \| `[^`]+` \| `([0-9a-f]{64})` \|", (VENDOR / "VENDOR.md").read_text()))
    assert set(table) == {"three.module.min.js", "OrbitControls.js", "LICENSE-three.txt"}
    for name, digest in table.items():
        assert hashlib.sha256((VENDOR / name).read_bytes()).hexdigest() == digest, name
    assert f'const t="{page.THREE_VERSION}"' in (VENDOR / "three.module.min.js").read_text()[:400]
