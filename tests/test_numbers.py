"""Every number of our results in the tables of studies/README.md and docs/ comes from a results file
(``docs/number_sources.py``, which the docs build also runs on every page it renders).

Independent check: the results files are written by the scripts that measured them; a number changed in a page
and not in its results file, or a results file regenerated without its page, fails here.
"""

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
_spec = importlib.util.spec_from_file_location("number_sources", ROOT / "docs" / "number_sources.py")
sources = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(sources)
NUMBER, found_in, parse, unsourced = sources.NUMBER, sources.found_in, sources.parse, sources.unsourced
_spec = importlib.util.spec_from_file_location("hooks", ROOT / "docs" / "hooks.py")
hooks = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(hooks)
PAGES = [ROOT / "studies" / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_number_of_ours_has_a_results_file(page):
    """The page as written by hand: its generated parts (``docs/hooks.py``) come from the code, not from results."""
    misses = unsourced(hooks.written(page.read_text()), str(page.relative_to(ROOT)))
    assert not misses, "\n".join(misses)


def test_the_check_catches_a_changed_number():
    """The checker itself: a cell copied from a results file passes; the same cell with one number changed in its
    last printed digit (to a value the file does not hold) fails, as does a number from no file."""
    source = "studies/li2022/results/uncontrolled_year.md"
    numbers = [n for n in NUMBER.findall((ROOT / source).read_text()) if "." in n and len(n) >= 6][:3]
    assert len(numbers) == 3
    page = f"## A section\n\nFrom `{source}`:\n\n| case | geojax |\n|---|---|\n| row | {' / '.join(numbers)} |\n"
    assert unsourced(page, "page") == []
    pool = [parse(n) for n in NUMBER.findall((ROOT / source).read_text())]
    last = numbers[-1]
    changed = next(last[:-1] + d for d in "0123456789" if not found_in([last[:-1] + d], pool))
    assert unsourced(page.replace(last, changed), "page")
    assert unsourced(page.replace(" |\n", " / 123.456789 |\n"), "page")
