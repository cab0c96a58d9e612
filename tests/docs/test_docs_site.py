r"""The documentation site, as a reader's browser shows it.

The site is built with ``python -m sphinx -W -b html docs <out>`` (warnings are errors: every internal reference
must resolve; the teaching notebooks and the examples are executed during the build), or taken ready-built from
``PSGSL_DOCS_HTML`` (``.ci/run`` builds it once with -W and points this test at it). A headless Chromium
(Debian's ``chromium``) then opens the home page and every teaching notebook's page over the DevTools protocol
(``tests/docs/_devtools.py`` says why that protocol and not ``--dump-dom``) and requires:

* no console error, no uncaught exception, no error in the browser's log, and no failed request for a file of the
  site;
* every page of the site, opened offline, requests nothing that leaves the machine (the site serves its own
  MathJax: a page read without network shows its formulas), every image on it decodes, and once MathJax has
  typeset the page no raw TeX (``\frac``, ``\mid``, ``$$`` …) is left in its text outside code;
* the page rendered: the theme's article holds text, and every image on it decodes;
* each notebook page holds its figures: executed outputs with ``image/png`` images, decoded by the browser —
  with matplotlib's Agg backend the notebooks would run and show no figure at all, which is what this catches.

Also checked on the built site: every public name of ``psgsl_pgm`` and its public packages has its entry in the
reference (the API pages are written from ``__all__``; this catches a page that failed to document a name).
Skipped, with the reason, when Chromium or (to build the site) Sphinx and its extensions are absent.
"""

from __future__ import annotations

import importlib
import os
import re
import subprocess
import sys
import urllib.parse
from pathlib import Path

import pytest

from ._devtools import Browser, find_chromium

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOKS = sorted(p.stem for p in (ROOT / "notebooks").glob("*.ipynb"))
PUBLIC_PACKAGES = ("psgsl_pgm", "psgsl_pgm.networks", "psgsl_pgm.olfaction", "psgsl_pgm.sim",
                   "psgsl_pgm.experiment", "psgsl_pgm.search", "psgsl_pgm.ros", "psgsl_pgm.teaching",
                   "psgsl_pgm.gym")
DOCS_EXTENSIONS = ("sphinx", "pydata_sphinx_theme", "numpydoc", "myst_nb", "sphinx_gallery",
                   "sphinx-mathjax-offline")

#: Every image of the page, eagerly loaded and decoded: [(src, decoded, inside a notebook cell's output), ...].
IMAGES_JS = """
Promise.all(Array.from(document.images).map(img => {
    img.loading = "eager";
    return img.decode().then(() => img.naturalWidth > 0, () => false)
        .then(ok => [img.getAttribute("src"), ok, img.closest(".cell_output") !== null]);
}))
"""
#: Every image of a notebook's executed outputs: [(src, alt text, caption of its figure), ...].
FIGURES_JS = """
Array.from(document.querySelectorAll(".cell_output img")).map(img => {
    const figure = img.closest("figure");
    const caption = figure ? figure.querySelector("figcaption") : null;
    return [img.getAttribute("src"), img.getAttribute("alt") || "", caption ? caption.innerText.trim() : ""];
})
"""
#: What the reader sees: the page title and the length of the article's text.
PAGE_JS = """
({title: document.title,
  article: (document.querySelector("article.bd-article") || {innerText: ""}).innerText.length,
  navbar: document.querySelectorAll(".bd-header a").length})
"""


#: After MathJax's first typesetting pass (the page's math is then rendered): the article's text outside code
#: blocks and inline code, where raw TeX would show.
TEXT_JS = """
(window.MathJax && MathJax.startup && MathJax.startup.promise ? MathJax.startup.promise : Promise.resolve())
.then(() => {
    const article = document.querySelector("article.bd-article") || document.body;
    const copy = article.cloneNode(true);
    copy.querySelectorAll("pre, code, .highlight, script, style, mjx-container").forEach(e => e.remove());
    return {text: copy.textContent, math: article.querySelectorAll("mjx-container").length,
            unrendered: article.querySelectorAll(".math:not(:has(mjx-container))").length};
})
"""
#: TeX that a reader must never see as text: a control word, or display-math dollars.
RAW_TEX = re.compile(r"\\(frac|mid|propto|sum|prod|alpha|beta|gamma|zeta|phi|varphi|tag|text|mathrm|left|right|"
                     r"cdot|neg|big|sqrt|int|lVert|rVert|stackrel|qquad)\b|\$\$")


def _pages(site: Path) -> list:
    """Every HTML page of the built site, except Sphinx's search page (it needs a server to run its index)."""
    return sorted(p for p in site.rglob("*.html") if p.name != "search.html" and "_static" not in p.parts)


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The built HTML site: ``PSGSL_DOCS_HTML`` if set, else built here with -W."""
    given = os.environ.get("PSGSL_DOCS_HTML")
    if given:
        html = Path(given).resolve()
        assert (html / "index.html").is_file(), f"PSGSL_DOCS_HTML={given} holds no index.html"
        return html
    missing = [m for m in DOCS_EXTENSIONS if importlib.util.find_spec(m) is None]
    if missing:
        pytest.skip(f"building the docs needs the docs extra (pip install -e \".[docs]\"): missing {missing}")
    html = tmp_path_factory.mktemp("docs") / "html"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    build = subprocess.run([sys.executable, "-m", "sphinx", "-W", "-q", "-b", "html", "docs", str(html)],
                           cwd=ROOT, env=env, capture_output=True, text=True, timeout=1800)
    assert build.returncode == 0, f"sphinx -W failed:\n{build.stdout[-4000:]}\n{build.stderr[-4000:]}"
    return html


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    executable = find_chromium()
    if executable is None:
        pytest.skip("no Chromium on PATH (Debian: apt-get install -y chromium)")
    chromium = Browser(executable, tmp_path_factory.mktemp("chromium-profile"))
    yield chromium
    chromium.close()


def _open(browser: Browser, page: Path) -> tuple[dict, list]:
    assert page.is_file(), f"the site has no {page}"
    browser.open(page.as_uri())
    images = browser.evaluate(IMAGES_JS)
    browser.evaluate("new Promise(done => setTimeout(done, 300))")  # late script errors
    errors, offline = browser.problems()
    assert errors == [], f"{page.name}: errors in the browser: {errors}"
    assert offline == [], f"{page.name}: requests to other hosts (the site must read offline): {offline}"
    broken = [src for src, ok, _ in images if not ok]
    assert broken == [], f"{page.name}: images that do not decode: {broken}"
    return browser.evaluate(PAGE_JS), images


@pytest.mark.slow
def test_home_page_renders_without_console_errors(site, browser):
    page, images = _open(browser, site / "index.html")
    assert "psgsl-pgm" in page["title"]
    assert page["article"] > 500, page
    assert page["navbar"] >= 5, f"the theme's header holds {page['navbar']} links"
    assert any("error-chart" in src for src, _, _ in images), "the home page lost its figure"


@pytest.mark.slow
@pytest.mark.parametrize("notebook", NOTEBOOKS)
def test_notebook_page_shows_its_figures(site, browser, notebook):
    page, images = _open(browser, site / "teaching" / "notebooks" / f"{notebook}.html")
    assert page["article"] > 500, page
    figures = [src for src, ok, in_output in images if in_output and ok]
    assert figures, f"{notebook}: no figure among the executed outputs (images: {images})"
    # every figure a notebook draws says what it shows: alt text for a reader who cannot see it, and a caption
    described = browser.evaluate(FIGURES_JS)
    bare = [src for src, alt, caption in described if not alt or alt == src or "_images/" in alt or not caption]
    assert bare == [], f"{notebook}: figures without alt text or caption: {bare}"
    # and the notebook itself, to run
    links = browser.evaluate("Array.from(document.querySelectorAll('a[download]')).map(a => a.href)")
    assert any(link.endswith(f"{notebook}.ipynb") for link in links), f"{notebook}: no download link: {links}"
    for link in links:
        assert Path(urllib.parse.unquote(urllib.parse.urlparse(link).path)).is_file(), f"{notebook}: {link} missing"


@pytest.mark.slow
def test_every_public_name_is_in_the_reference(site):
    for package in PUBLIC_PACKAGES:
        importlib.import_module(package)
    anchors = set()
    for page in (site / "reference" / "api").rglob("*.html"):
        anchors.update(re.findall(r'<dt class="sig sig-object py" id="([\w.]+)"', page.read_text()))
    documented = {}
    for name in anchors:
        module, _, attr = name.rpartition(".")
        if module in sys.modules and hasattr(sys.modules[module], attr):
            documented.setdefault(id(getattr(sys.modules[module], attr)), name)
    missing = []
    for package in PUBLIC_PACKAGES:
        module = importlib.import_module(package)
        for name in module.__all__:
            full = f"{package}.{name}"
            if full not in anchors and id(getattr(module, name)) not in documented:
                missing.append(full)
    assert missing == [], f"public names without a reference entry: {missing}"


def _left_the_machine(url: str) -> bool:
    return not url.startswith(("file://", "data:", "blob:", "about:", "chrome-extension:", "devtools:"))


@pytest.mark.slow
def test_every_page_reads_offline_with_its_math_typeset_and_its_images(site, browser):
    """Each page of the site, opened from disk: no request off the machine, no raw TeX, every image decoded."""
    failures = []
    for page in _pages(site):
        name = page.relative_to(site).as_posix()
        browser.open(page.as_uri())
        images = browser.evaluate(IMAGES_JS)
        shown = browser.evaluate(TEXT_JS)
        outside = sorted({url for url in browser.requests() if _left_the_machine(url)})
        if outside:
            failures.append(f"{name}: requests that leave the machine: {outside[:3]}")
        broken = [src for src, ok, _ in images if not ok]
        if broken:
            failures.append(f"{name}: images that do not decode: {broken[:3]}")
        raw = RAW_TEX.search(shown["text"])
        if raw or shown["unrendered"]:
            where = shown["text"][max(0, raw.start() - 40):raw.end() + 40] if raw else ""
            failures.append(f"{name}: raw TeX {where!r}, {shown['unrendered']} math element(s) not typeset")
    assert failures == [], "\n".join(failures)


@pytest.mark.slow
def test_the_math_is_typeset_by_the_sites_own_mathjax(site, browser):
    """The equations page shows the paper's numbers, typeset by the MathJax copy under _static/."""
    assert (site / "_static" / "mathjax" / "tex-chtml.js").is_file()
    browser.open((site / "reference" / "equations.html").as_uri())
    shown = browser.evaluate(TEXT_JS)
    assert shown["math"] >= 4, shown["math"]
    scripts = [url for url in browser.requests() if "mathjax" in url.lower()]
    assert scripts and all(url.startswith("file://") for url in scripts), scripts
    # MathJax draws a tag's number as the label column of its table, with the id mjx-eqn:<tag>
    tags = browser.evaluate("""Array.from(document.querySelectorAll('mjx-labels mjx-mtd[id^="mjx-eqn:"]'))
                               .map(e => e.id)""")
    assert tags == ["mjx-eqn:1", "mjx-eqn:11", "mjx-eqn:15", "mjx-eqn:20"], tags
