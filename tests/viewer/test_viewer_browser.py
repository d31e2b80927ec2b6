"""The page of ``symkin view`` in a real browser (issue 19): headless Chromium moves sliders and the page
shows what numpy computes; the workspace cloud toggles; screenshots are not blank.

The page evaluates the generated JavaScript, so its TCP position matches numpy's to the backends'
agreement (relative 1e-12, tests/backends/test_js_backend.py); its 1/kappa comes from its own Jacobi SVD,
within the rounding of two backward-stable SVDs (tests/tolerances.py: svd) of LAPACK's.  No browser
is a failure, not a skip: .ci/run installs Debian's chromium.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from browser import chromium, drawn, open_page, pixels
from sample_models import dual_scara_text
from symkin import load, pipeline
from symkin.numerics import conditioning
from symkin.analysis import global_indices
from symkin.mechanism import reach
from symkin.model import model_from_text
from symkin.runtime.parallel import closure_velocities, solve_closure
from symkin.viewer import page as viewer_page
from tolerances import KINEMATICS, NEWTON, svd

AGREEMENT = 1e-12
pytestmark = pytest.mark.xdist_group("browser")


@pytest.fixture(scope="module")
def browser():
    with chromium() as b:
        yield b


@pytest.fixture(scope="module")
def pages(generated_dir, tmp_path_factory):
    """name -> the page of the generated model (1024 cloud points), written as symkin view writes it."""
    out = tmp_path_factory.mktemp("pages")
    written = {}
    for name in ("ur10e", "delta", "stewart", "delta_wrist"):
        written[name] = out / f"{name}.html"
        written[name].write_text(viewer_page.page_of(load(generated_dir / name), 1024)[0])
    return written


def press(page, slider: str, key: str, times: int) -> None:
    page.focus(f"#{slider}")
    for _ in range(times):
        page.keyboard.press(key)


def shown_tcp(page) -> tuple[np.ndarray, np.ndarray]:
    """(the TCP position the page holds, in m; the one it prints, in mm)."""
    tcp = page.locator("#tcp")
    held = np.array([float(tcp.get_attribute(f"data-{axis}")) for axis in "xyz"])
    printed = np.array([float(v) for v in re.findall(r"-?\d+\.\d+", tcp.inner_text())])
    return held, printed


def shown_inverse_kappa(page) -> float:
    return float(page.locator("#inverse-kappa").get_attribute("data-value"))


def test_a_joint_slider_moves_the_arm_to_numpys_fk(browser, pages, generated_dir):
    model = load(generated_dir / "ur10e")
    page = open_page(browser, pages["ur10e"])
    before = np.array(page.evaluate("window.symkinView.state.q"))
    press(page, "joint-q2", "ArrowRight", 25)  # 0.1 deg per step
    q = np.array(page.evaluate("window.symkinView.state.q"))
    assert q[1] - before[1] == pytest.approx(np.radians(2.5), abs=1e-9)
    assert np.array_equal(q[[0, 2, 3, 4, 5]], before[[0, 2, 3, 4, 5]])
    held, printed = shown_tcp(page)
    want = model.fk(q)[:3, 3]
    np.testing.assert_allclose(held, want, rtol=0, atol=AGREEMENT * np.abs(want).max())
    np.testing.assert_allclose(printed, 1000 * want, rtol=0, atol=0.0005 + 1e-9)  # printed to 3 decimals (mm)
    length = page.evaluate("JSON.parse(document.getElementById('symkin-data').textContent).conditioning.length")
    expected = float(global_indices.local_index(model, q, length=length))
    assert shown_inverse_kappa(page) == pytest.approx(expected, abs=AGREEMENT + svd(6))
    assert int(page.evaluate("document.body.dataset.updates")) == 26
    assert not page.errors


def test_the_delta_follows_its_tcp_through_the_closed_form_ik(browser, pages, generated_dir):
    model = load(generated_dir / "delta")
    page = open_page(browser, pages["delta"])
    press(page, "task-x", "ArrowRight", 40)   # 4 mm
    press(page, "task-z", "ArrowLeft", 30)    # 3 mm down
    p = np.array(page.evaluate("window.symkinView.state.p"))
    np.testing.assert_allclose(p, [0.004, 0.0, -0.153], rtol=0, atol=1e-12)
    q = np.array(page.evaluate("window.symkinView.state.q"))
    np.testing.assert_allclose(q, model.ik(p).joints, rtol=0, atol=AGREEMENT)
    held, printed = shown_tcp(page)
    np.testing.assert_array_equal(held, p)
    np.testing.assert_allclose(printed, 1000 * p, atol=0.0005 + 1e-9)
    expected = float(global_indices.local_index(model, q))
    assert shown_inverse_kappa(page) == pytest.approx(expected, abs=AGREEMENT + svd(3))
    assert page.locator("#warning").is_hidden()


def test_the_stewart_platform_is_rated_by_its_twist_jacobian(browser, pages, generated_dir):
    model = load(generated_dir / "stewart")
    page = open_page(browser, pages["stewart"])
    press(page, "task-roll", "ArrowRight", 30)  # 3 deg
    press(page, "task-yaw", "ArrowLeft", 20)    # -2 deg
    p = np.array(page.evaluate("window.symkinView.state.p"))
    q = np.array(page.evaluate("window.symkinView.state.q"))
    np.testing.assert_allclose(q, model.ik(p).joints, rtol=0, atol=AGREEMENT * np.abs(q).max())
    held = reach.ConstantOrientation(model, p[3:])
    length = page.evaluate("JSON.parse(document.getElementById('symkin-data').textContent).conditioning.length")
    J = conditioning.homogenize(held.jacobian(q, p[:3]), length, (0, 1, 2))
    expected = float(conditioning.inverse_condition_number(J))
    # J = diag(I, E) inv(J^-1): an inversion, whose rounding kappa(J^-1) amplifies, before the SVD
    assert shown_inverse_kappa(page) == pytest.approx(expected, rel=AGREEMENT * np.linalg.cond(J), abs=svd(6))


def test_a_hybrid_device_shows_its_wrist_on_the_platform(browser, pages, generated_dir):
    """The wrist's sliders turn its joints on the platform the task sliders move: the TCP the page shows is the
    wrist's (numpy's device_fk), its links are drawn, and its 1/kappa is that of the angular rows of
    device_jacobian in the wrist's columns: tan(45 deg - |psi2| / 2) for this Z-X-Y wrist (docs/analysis.md)."""
    model = load(generated_dir / "delta_wrist")
    page = open_page(browser, pages["delta_wrist"])
    assert page.evaluate("window.symkinView.state.qw") == [0.0, 0.0, 0.0]
    press(page, "task-x", "ArrowRight", 20)    # 2 mm
    for slider, degrees in (("wrist-psi1", 30.0), ("wrist-psi2", -40.0)):  # as a drag: one input event each
        page.eval_on_selector(f"#{slider}", "(e, v) => { e.value = v; e.dispatchEvent(new Event('input')); }",
                              degrees)
    p = np.array(page.evaluate("window.symkinView.state.p"))
    qw = np.array(page.evaluate("window.symkinView.state.qw"))
    np.testing.assert_allclose(qw, np.radians([30.0, -40.0, 0.0]), rtol=0, atol=1e-12)
    held, printed = shown_tcp(page)
    want = model.device_fk(p, qw)[:3, 3]
    np.testing.assert_allclose(held, want, rtol=0, atol=AGREEMENT * np.abs(want).max())
    np.testing.assert_allclose(printed, 1000 * want, rtol=0, atol=0.0005 + 1e-9)
    wrist = float(page.locator("#wrist-kappa").get_attribute("data-value"))
    assert wrist == pytest.approx(np.tan(np.radians(45.0 - 20.0)), abs=AGREEMENT + svd(3))
    drawn_wrist = page.evaluate("window.symkinView.evaluate().wrist")
    frames = model.device_frames(p, qw)
    expected = [p] + [T[:3, 3] for T in frames] + [want]
    np.testing.assert_allclose(np.array(drawn_wrist), np.array(expected), rtol=0, atol=AGREEMENT)
    assert not page.errors


def test_the_cloud_toggles_and_the_screenshots_are_not_blank(browser, pages, tmp_path):
    page = open_page(browser, pages["delta"])
    canvas = page.locator("#view")
    with_cloud = canvas.screenshot(path=str(tmp_path / "with-cloud.png"))
    assert page.evaluate("window.symkinView.cloud.visible")
    assert page.locator("#colour-bar").is_visible()
    page.click("#show-cloud")
    assert not page.evaluate("window.symkinView.cloud.visible")
    assert page.locator("#colour-bar").is_hidden()
    without = canvas.screenshot(path=str(tmp_path / "without-cloud.png"))
    a, b = pixels(with_cloud), pixels(without)
    assert drawn(a)
    assert drawn(b)
    changed = np.any(np.abs(a - b) > 0.05, axis=-1).mean()
    assert changed > 0.005, f"hiding the cloud changed {changed:.2%} of the pixels"
    page.click("#show-cloud")
    assert page.evaluate("window.symkinView.cloud.visible")


def test_the_cloud_is_recomputed_for_a_moved_design(browser, pages, generated_dir):
    """A design slider moves; the page recomputes the cloud from the same joint samples through the generated
    JavaScript: the points and 1/kappa are numpy's for the new design (where the mechanism still assembles)."""
    page = open_page(browser, pages["delta"])
    assert page.locator("#cloud-note").is_hidden()
    press(page, "param-a", "ArrowRight", 100)  # upper arm 100 -> 110 mm
    assert page.locator("#cloud-note").is_visible()
    page.click("#recompute-cloud")
    assert page.locator("#cloud-note").is_hidden()
    a = page.evaluate("window.symkinView.state.params.a")
    assert a == pytest.approx(0.11, abs=1e-12)
    samples = np.array(page.evaluate("JSON.parse(document.getElementById('symkin-data').textContent).cloud.samples"))
    shown = page.evaluate("window.symkinView.cloud.userData")
    model = load(generated_dir / "delta").bind(a=a)
    with np.errstate(invalid="ignore"):  # samples where the longer arms no longer assemble: NaN, margin < 0
        position, margin = model.fk(samples)
    assembled = margin >= 0
    np.testing.assert_allclose(np.array(shown["points"]), position[assembled], rtol=0, atol=AGREEMENT)
    expected = global_indices.local_index(model, samples[assembled])
    np.testing.assert_allclose(np.array(shown["values"]), expected, rtol=0, atol=AGREEMENT + svd(3))
    ticks = page.locator("#colour-ticks span").all_inner_texts()
    assert ticks[-1] == f"{max(shown['values']):.2f}"


#: The dual SCARA's lifts: its model file declares no stroke (tests/sample_models.py).
SCARA_STROKE = (0.0, 0.2)


@pytest.fixture(scope="module")
def scara_page(tmp_path_factory):
    """(the dual SCARA's model, numpy; its page with about 512 cloud cells, as symkin view writes it; the cloud)."""
    model = model_from_text(dual_scara_text(), file="dual_scara.yaml")
    request = pipeline.resolve_request(model, "closure,closure_jacobians,leg_joints", "numpy,js")
    directory = pipeline.write(pipeline.generate(model, request), tmp_path_factory.mktemp("scara"))
    loaded = load(directory)
    html, cloud = viewer_page.page_of(loaded, 512, limits={"lift1": SCARA_STROKE})
    path = directory.parent / "dual_scara.html"
    path.write_text(html)
    return loaded, path, cloud


def _scara_inverse_kappa(model, q, s, p, length) -> np.ndarray:
    """1/kappa as symkin workspace rates the dual SCARA: J = dp/dq from the closure (its yaw row a rate already),
    homogenized by the page's characteristic length."""
    J = conditioning.homogenize(closure_velocities(model, q, s, p).J, length, (0, 1, 2))
    return conditioning.inverse_condition_number(J)


def test_legs_of_any_topology_follow_the_platform_by_newton_on_their_closure(browser, scara_page):
    """The task sliders move the bar; the page solves the closure for (q, s) from its last assembly in the generated
    JavaScript: the legs close where numpy's Gauss-Newton from the home assembly closes them (the same working
    mode), the joints drawn are leg_joints there, and 1/kappa is that of numpy's closure_velocities."""
    model, html, _ = scara_page
    assert "<h2>Platform (legs solved by Gauss-Newton on the loop closure, from the home assembly)</h2>" in \
        html.read_text()
    page = open_page(browser, html)
    q0, s0 = (np.array(page.evaluate(f"window.symkinView.state.{v}")) for v in "qs")
    press(page, "task-x", "ArrowRight", 20)     # 2 mm
    press(page, "task-yaw", "ArrowRight", 30)   # 3 deg
    p = np.array(page.evaluate("window.symkinView.state.p"))
    np.testing.assert_allclose(p, [0.002, 0.3, 0.1, np.radians(3.0)], rtol=0, atol=1e-12)
    q, s = (np.array(page.evaluate(f"window.symkinView.state.{v}")) for v in "qs")
    assert np.max(np.abs(model.closure(q, s, p))) <= NEWTON
    report = solve_closure(model, q0, s0, p, unknowns=("q", "s"), max_step=0.2)
    assert report.all_converged
    turned = np.angle(np.exp(1j * (q - report.solution["q"])))   # angles on the page: within the limits' turn
    turned[1] = q[1] - report.solution["q"][1]                    # the lift: a length
    Phi = model.closure_jacobians(q, s, p)
    # two converged solves: each within NEWTON of the closure, so within kappa([Phi_q Phi_s]) NEWTON of the root
    np.testing.assert_allclose(turned, 0.0, atol=2 * NEWTON * np.linalg.cond(np.hstack([Phi.Phi_q, Phi.Phi_s])))
    drawn_legs = page.evaluate("window.symkinView.evaluate().legs")
    for shown, want in zip(drawn_legs, model.leg_joints(q, s)):
        np.testing.assert_allclose(np.array(shown), want, rtol=0, atol=AGREEMENT)
    length = page.evaluate("JSON.parse(document.getElementById('symkin-data').textContent).conditioning.length")
    expected = float(_scara_inverse_kappa(model, q, s, p, length))
    assert shown_inverse_kappa(page) == pytest.approx(expected, abs=AGREEMENT + svd(4))
    assert page.locator("#warning").is_hidden()
    assert not page.errors


def test_the_cloud_of_legs_of_any_topology_is_solved_again_for_a_moved_design(browser, scara_page):
    """The page's cloud is the working mode's cells (symkin.analysis.continued_workspace); for a moved design each
    cell is solved again from its (q, s) at load, and its 1/kappa is numpy's at the new design's assembly."""
    model, html, cloud = scara_page
    page = open_page(browser, html)
    shown = page.evaluate("window.symkinView.cloud.userData")
    np.testing.assert_allclose(np.array(shown["points"]), cloud.points, rtol=0, atol=1e-6)   # CLOUD_DIGITS
    assert len(shown["points"]) >= 256                                                       # about 512 asked
    press(page, "param-l1", "ArrowRight", 100)   # first links 250 -> 260 mm
    page.click("#recompute-cloud")
    l1 = page.evaluate("window.symkinView.state.params.l1")
    assert l1 == pytest.approx(0.26, abs=1e-12)
    recomputed = page.evaluate("window.symkinView.cloud.userData")
    assert len(recomputed["points"]) >= len(shown["points"]) // 2
    moved = model.bind(l1=l1)
    data = page.evaluate("JSON.parse(document.getElementById('symkin-data').textContent)")
    samples = {tuple(np.round(platform, 9)): sample for sample in data["cloud"]["samples"]
               for platform in [sample["p"][:3]]}
    for point, value in zip(recomputed["points"][:64], recomputed["values"][:64]):
        sample = samples[tuple(np.round(point, 9))]
        report = solve_closure(moved, sample["q"], sample["s"], sample["p"], unknowns=("q", "s"), max_step=0.2)
        want = _scara_inverse_kappa(moved, report.solution["q"], report.solution["s"], np.array(sample["p"]),
                                    data["conditioning"]["length"])
        Phi = moved.closure_jacobians(report.solution["q"], report.solution["s"], sample["p"])
        # the page solves for J by the normal equations, whose error grows with kappa(B)^2 (Higham sec. 20.4),
        # B = [Phi_p Phi_s]; numpy's by an orthogonal projector (kappa(B))
        allowed = KINEMATICS * np.linalg.cond(np.hstack([Phi.Phi_p, Phi.Phi_s])) ** 2 + svd(4)
        assert value == pytest.approx(float(want), abs=allowed)
    assert not page.errors
