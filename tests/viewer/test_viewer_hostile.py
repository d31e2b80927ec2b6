"""Pages made from hostile model files and URDFs (issue 28): ``symkin view`` writes each page (or refuses
with a located message, exit 2), the page holds only the elements and scripts of its template, and in
headless Chromium no injected element exists, no injected script runs and the viewer still draws;
inside a notebook's sandboxed iframe too.  The texts: tests/hostile_text.py."""

from __future__ import annotations

import html
import html.parser
import re
from pathlib import Path

import pytest

from browser import VIEWPORT, chromium, drawn, pixels
from hostile_text import MARKER_PREFIX, NAME_CASES, TEXT_CASES, model_text, urdf_text
import symkin
from symkin.cli import main
from symkin.viewer import page as viewer_page

pytestmark = pytest.mark.xdist_group("browser")
#: Cloud points of each page: enough to draw, few to sample.
SAMPLES = "64"
SOURCES = [(case, kind) for case, _ in TEXT_CASES for kind in ("yaml", "urdf")]


class Elements(html.parser.HTMLParser):
    """The tags and attribute names a page's markup holds (script and style content is not markup)."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.tags: list[str] = []
        self.attributes: set[str] = set()

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.tags.append(tag)
        self.attributes.update(name for name, _ in attrs)


def elements(document: str) -> Elements:
    parsed = Elements()
    parsed.feed(document)
    parsed.close()
    return parsed


def stem(case: str) -> str:
    return "arm_" + case.replace("-", "_")


@pytest.fixture(scope="module")
def pages(tmp_path_factory) -> dict[tuple[str, str], Path]:
    """(case, yaml|urdf) -> the page ``symkin view`` wrote from a model file holding the case in every
    free-text field, or from a URDF whose robot name is the case."""
    root = tmp_path_factory.mktemp("hostile-pages")
    written = {}
    for case, text in TEXT_CASES + [("plain", "a planar arm")]:
        for kind, source in (("yaml", model_text(text)), ("urdf", urdf_text(text))):
            path = root / f"{stem(case)}.{kind}"  # a URDF's model takes its file's name
            path.write_text(source, encoding="utf-8")
            out = root / f"{case}-{kind}.html"
            assert main(["view", str(path), "-o", str(out), "--workspace", SAMPLES]) == 0, (case, kind)
            written[case, kind] = out
    return written


@pytest.fixture(scope="module")
def reference(pages) -> Elements:
    """The markup of a page made from a plain model file: what every hostile page must hold, no more."""
    return elements(pages["plain", "yaml"].read_text(encoding="utf-8"))


@pytest.fixture(scope="module")
def browser():
    with chromium() as b:
        yield b


@pytest.mark.parametrize("case,kind", SOURCES, ids=[f"{c}-{k}" for c, k in SOURCES])
def test_a_hostile_page_holds_only_its_templates_markup(case, kind, pages, reference):
    document = pages[case, kind].read_text(encoding="utf-8")
    found = elements(document)
    assert found.tags == reference.tags
    assert found.attributes == reference.attributes
    assert not any(name.startswith("on") for name in found.attributes)
    # the text reads as text: the description paragraph shows it, unescaped once by the browser's parser
    text = dict(TEXT_CASES)[case]
    description = re.search(r"<h1>.*?</h1>\s*<p>(.*?)</p>", document, re.S).group(1)
    assert " ".join(text.split())[:200] in " ".join(html.unescape(description).split())
    # every inline script is pinned by its hash in the Content-Security-Policy
    scripts = re.findall(r"<script(?: type=\"(?:module|importmap)\")?>(.*?)</script>", document, re.S)
    policy = html.unescape(re.search(r'http-equiv="Content-Security-Policy" content="([^"]*)"', document).group(1))
    assert len(scripts) == 3
    assert viewer_page.content_security_policy(scripts) == policy


def _injected(page) -> dict:
    """What a payload would leave: markers on window, a changed title, elements the template has none of."""
    return page.evaluate(f"""() => ({{
        markers: Object.getOwnPropertyNames(window).filter((k) => k.startsWith({MARKER_PREFIX!r})),
        title: document.title,
        foreign: document.querySelectorAll("img, svg, iframe, base, object, embed, form, b, a").length,
        styles: document.querySelectorAll("style").length,
        metas: document.querySelectorAll("meta").length,
    }})""")


@pytest.mark.parametrize("kind", ["yaml", "urdf"])
def test_no_injected_element_or_script_and_the_viewer_draws(kind, pages, browser):
    """One tab goes through the pages (a new document each: nothing carries over but the tab's cost)."""
    page = browser.new_page(viewport=VIEWPORT)
    problems: list[str] = []
    page.on("pageerror", lambda error: problems.append(str(error)))
    page.on("console", lambda message: problems.append(message.text) if message.type == "error" else None)
    for case, _ in TEXT_CASES:
        page.goto(pages[case, kind].resolve().as_uri())
        page.wait_for_selector("body[data-ready='1']", state="attached", timeout=30_000)
        page.wait_for_timeout(20)  # a timer- or load-driven payload would have run by now
        found = _injected(page)
        assert found == {"markers": [], "title": f"{'arm' if kind == 'yaml' else stem(case)}: symkin view",
                         "foreign": 0, "styles": 1, "metas": 2}, (case, found)
        assert drawn(pixels(page.locator("#view").screenshot())), case
        assert not problems, (case, problems)  # no script error, no Content-Security-Policy violation
    page.close()


def test_the_notebook_frame_is_sandboxed_and_the_viewer_works_in_it(tmp_path, browser):
    """The inline representation runs its scripts in an opaque origin: the viewer draws, and it cannot read
    its parent (which a page without allow-same-origin must not)."""
    path = tmp_path / "model.yaml"
    path.write_text(model_text(dict(TEXT_CASES)["img-onerror"]), encoding="utf-8")
    assert main(["derive", str(path), "-o", str(tmp_path / "out"), "--backend", "numpy,js",
                 "--only", "fk,frames,jacobian", "-q"]) == 0
    shown = symkin.load(tmp_path / "out" / "arm")._repr_html_()
    assert 'sandbox="allow-scripts"' in shown
    assert "allow-same-origin" not in shown
    notebook = tmp_path / "notebook.html"
    notebook.write_text(f"<!DOCTYPE html><html><body><script>window.secret = 42;</script>{shown}</body></html>")
    page = browser.new_page()
    page.goto(notebook.resolve().as_uri())
    (frame,) = [f for f in page.frames if f != page.main_frame]
    frame.wait_for_selector("body[data-ready='1']", state="attached", timeout=30_000)
    assert frame.evaluate("window.origin") == "null"
    assert frame.evaluate("(() => { try { return String(parent.secret); } catch (e) { return 'blocked'; } })()") \
        == "blocked"
    assert drawn(pixels(frame.locator("#view").screenshot()))
    assert page.evaluate("document.title") == ""
    assert not page.evaluate(f"Object.getOwnPropertyNames(window).filter((k) => k.startsWith({MARKER_PREFIX!r}))")
    page.close()


def test_a_tampered_model_script_is_refused_with_exit_2(tmp_path, capsys):
    """A generated directory whose JavaScript was edited to end the page's script element is not inlined."""
    path = tmp_path / "model.yaml"
    path.write_text(model_text("a planar arm"), encoding="utf-8")
    assert main(["derive", str(path), "-o", str(tmp_path), "--backend", "numpy,js", "--only", "fk,frames,jacobian",
                 "-q"]) == 0
    directory = tmp_path / "arm"
    script = directory / "arm.js"
    script.write_text(script.read_text() + "\n// </script><script>window.pwned = 1</script>\n")
    out = tmp_path / "page.html"
    with pytest.raises(SystemExit) as exit_:
        main(["view", str(directory), "-o", str(out)])
    err = capsys.readouterr().err
    assert exit_.value.code == 2
    assert f"{script}" in err
    assert "</script" in err
    assert "derive the model again" in err
    assert not out.exists()


@pytest.mark.parametrize("case,name", NAME_CASES, ids=[c for c, _ in NAME_CASES])
def test_hostile_names_give_a_page_or_a_located_refusal(case, name, tmp_path, capsys):
    """A name (of a model file's parameter; of a URDF's joint and link) either names a slider of a page that
    holds the template's markup, or is refused where it stands with exit code 2 and no page."""
    for kind, source in (("yaml", model_text("a planar arm", parameter=name)),
                         ("urdf", urdf_text("arm", joint=name, link=name))):
        path = tmp_path / f"arm.{kind}"
        path.write_text(source, encoding="utf-8")
        out = tmp_path / f"{kind}.html"
        code = main(["view", str(path), "-o", str(out), "--workspace", SAMPLES])
        err = capsys.readouterr().err
        if code == 2:
            assert f"{path}:" in err, err
            assert "fix:" in err, err
            assert "Traceback" not in err, err
            assert not out.exists(), err
            continue
        assert code == 0, err
        found = elements(out.read_text(encoding="utf-8"))
        assert not any(attribute.startswith("on") for attribute in found.attributes)
        assert set(found.tags) <= {"html", "head", "meta", "title", "style", "body", "div", "h1", "h2", "p", "span",
                                   "label", "input", "button", "canvas", "script"}
