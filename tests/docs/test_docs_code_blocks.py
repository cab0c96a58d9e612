"""Every Python block of the docs' pages runs (the user guide's examples are code a reader copies).

The pages are Markdown under docs/; a fenced block marked ``python`` is executed as it stands, each in a fresh
namespace, from a temporary working directory. Blocks that need an extra are run with it installed (the test
extra holds every extra).
"""

import re
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[2] / "docs"
PAGES = sorted(p for p in DOCS.rglob("*.md") if "_build" not in p.parts and not p.is_symlink()
               and "notebooks" not in p.parts)
BLOCKS = [(page, i, block) for page in PAGES
          for i, block in enumerate(re.findall(r"```python\n(.*?)```", page.read_text(), flags=re.S))]


def test_the_guide_has_python_examples():
    assert len(BLOCKS) >= 4, [f"{p.relative_to(DOCS)}#{i}" for p, i, _ in BLOCKS]


GUIDES = [DOCS / "getting-started.md", *sorted(p for p in (DOCS / "guide").glob("*.md") if p.name != "index.md")]


@pytest.mark.parametrize("page", GUIDES, ids=[p.stem for p in GUIDES])
def test_every_guide_shows_runnable_python(page):
    """Each guide page (and getting started) holds at least one ```python block, which the test below runs."""
    assert any(p == page for p, _, _ in BLOCKS), f"{page.relative_to(DOCS)} has no ```python block"


@pytest.mark.parametrize("page,index,block", BLOCKS,
                         ids=[f"{p.relative_to(DOCS).with_suffix('')}-{i}" for p, i, _ in BLOCKS])
def test_docs_python_block_runs(page, index, block, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    exec(compile(block, f"{page}#block{index}", "exec"), {"__name__": "docs_example"})


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(DOCS)) for p in PAGES])
def test_docs_page_describes_the_software_not_its_history(page):
    text = page.read_text()
    assert not re.search(r"load average|\bissue \d+|`[0-9a-f]{7,40}`", text, flags=re.I), \
        f"{page.name}: no load averages, issue numbers or commit hashes in user-facing text"
