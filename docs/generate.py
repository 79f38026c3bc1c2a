"""Write the generated parts of ``docs/*.md`` from the code (``docs/hooks.py`` makes them; the built site fills the
same parts the same way), so the pages read on disk hold every table the site shows.

    python docs/generate.py           # rewrite the pages whose generated parts are stale
    python docs/generate.py --check   # list them and exit 1, writing nothing

Run it after changing a scenario key, a controller's keys, a command's options, a metric's meaning, an exported
name, a module's docstring or ``studies/README.md``; ``tests/test_docs.py`` fails until it is run.
"""

from __future__ import annotations

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS.parent))  # the geojax of this checkout, as the site's build imports it
import hooks  # noqa: E402  (docs/ is this script's folder: on the path when it runs, and for the tests)

COMMAND = "python docs/generate.py"


def stale() -> dict[Path, str]:
    """Every page whose generated parts differ from what the code makes now, with the page as it should be."""
    pages = {}
    for page in sorted(DOCS.glob("*.md")):
        text = page.read_text()
        fresh = hooks.fill(text, page.name)
        if fresh != text:
            pages[page] = fresh
    return pages


def main(argv: list[str]) -> int:
    pages = stale()
    for page, fresh in pages.items():
        if "--check" not in argv:
            page.write_text(fresh)
        print(f"{'stale' if '--check' in argv else 'wrote'}: {page.relative_to(DOCS.parent)}")
    return 1 if pages and "--check" in argv else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
