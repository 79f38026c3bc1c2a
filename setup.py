"""Packaging hook (the project is declared in pyproject.toml): record the git commit being built.

``geojax.store.source_revision`` reads the checkout's git where geojax runs from one; an installed copy
(``pip install .`` from a clone) has no ``.git`` beside it, so the build writes the commit, with ``+dirty``
for uncommitted changes, to ``geojax/_revision.txt`` in the built package.  Outside a git checkout (an
sdist) nothing is written and files say "unknown".
"""

import importlib.util
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py


def git_revision(root: Path) -> str | None:
    """``geojax/_git.py``'s revision, loaded by path (the package's dependencies are not there at build time)."""
    spec = importlib.util.spec_from_file_location("geojax_git", root / "geojax" / "_git.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.revision(root)


class BuildWithRevision(build_py):
    def run(self):
        super().run()
        revision = git_revision(Path(__file__).resolve().parent)
        if revision and not self.dry_run:
            target = Path(self.build_lib) / "geojax" / "_revision.txt"
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_text(revision + "\n")


setup(cmdclass={"build_py": BuildWithRevision})
