"""Headless Chromium for the viewer's tests (Debian's ``chromium`` driven by Playwright; no browser
download), and ``python tests/browser.py OUT_DIR``: the screenshots of docs/viewer.md.

Chromium is started as the machine's notes say it runs here: no sandbox (root in CI), no GPU (WebGL
through SwiftShader, which Chromium enables only when asked), no background connections (the
network is closed).
"""

from __future__ import annotations

import contextlib
import io
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np

CHROMIUM = os.environ.get("SYMKIN_CHROMIUM", "/usr/bin/chromium")
ARGS = ["--headless=new", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader", "--disable-quic",
        "--no-first-run", "--disable-background-networking", "--disable-component-update", "--disable-sync"]
VIEWPORT = {"width": 1280, "height": 800}


@contextlib.contextmanager
def chromium() -> Iterator:
    """A Playwright browser on Debian's chromium; a missing browser is an error, not a skip."""
    from playwright.sync_api import sync_playwright

    assert Path(CHROMIUM).is_file(), (f"no Chromium at {CHROMIUM}: install Debian's chromium (apt-get install "
                                      "chromium; .ci/run does) or set SYMKIN_CHROMIUM")
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        try:
            yield browser
        finally:
            browser.close()


def open_page(browser, html: Path):
    """The page of ``html``, loaded and drawn (body[data-ready]); page errors are collected in page.errors."""
    page = browser.new_page(viewport=VIEWPORT)
    page.errors = []
    page.on("pageerror", lambda error: page.errors.append(str(error)))
    page.goto(html.resolve().as_uri())
    page.wait_for_selector("body[data-ready='1']", state="attached", timeout=30_000)
    assert not page.errors, page.errors
    return page


def pixels(png: bytes) -> np.ndarray:
    """An RGB(A) image (h, w, c) of PNG bytes."""
    import matplotlib.image

    return matplotlib.image.imread(io.BytesIO(png), format="png")


def drawn(image: np.ndarray) -> bool:
    """Whether an image shows something: many distinct colours, not one flat background."""
    rgb = (image[..., :3] * 255).astype(np.uint32).reshape(-1, 3)
    colours = np.unique((rgb[:, 0] << 16) | (rgb[:, 1] << 8) | rgb[:, 2])  # one integer per colour: fast
    return len(colours) > 64 and float(image[..., :3].std()) > 0.02


SCREENSHOTS = {  # docs/images/<name>: the model directory and what to show
    "viewer-ur10e.png": ("ur10e", {}),
    "viewer-delta.png": ("delta", {}),
    "viewer-stewart.png": ("stewart", {"task-roll": 60, "task-z": -150}),
}


def screenshots(out: Path, generated: Path) -> None:
    """Write the docs' screenshots: each page as it opens, its sliders moved by arrow keys."""
    out.mkdir(parents=True, exist_ok=True)
    with chromium() as browser:
        for name, (model, moves) in SCREENSHOTS.items():
            html = out / f"{model}.html"
            subprocess.run([sys.executable, "-m", "symkin", "view", str(generated / model), "-o", str(html)], check=True)
            page = open_page(browser, html)
            for slider, steps in moves.items():
                page.focus(f"#{slider}")
                for _ in range(abs(steps)):
                    page.keyboard.press("ArrowRight" if steps > 0 else "ArrowLeft")
            page.screenshot(path=str(out / name))
            html.unlink()
            page.close()


if __name__ == "__main__":
    screenshots(Path(sys.argv[1]), Path(sys.argv[2]) if len(sys.argv) > 2 else Path("generated"))
