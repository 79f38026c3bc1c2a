"""Packaging hook (the project is declared in pyproject.toml): record the git commit being built.

``geojax.store.source_revision`` reads the checkout's git where geojax runs from one; an installed copy
(``pip install .`` from a clone) has no ``.git`` beside it, so the build writes the commit, with ``+dirty``
for uncommitted changes, to ``geojax/_revision.txt`` in the built package.  Outside a git checkout (an
sdist) nothing is written and files say "unknown".
"""

import subprocess
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py


def git_revision(root: Path) -> str | None:
    try:
        head = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True,
                              timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None
    return (head + ("+dirty" if dirty else "")) if head else None


class BuildWithRevision(build_py):
    def run(self):
        super().run()
        revision = git_revision(Path(__file__).resolve().parent)
        if revision and not self.dry_run:
            target = Path(self.build_lib) / "geojax" / "_revision.txt"
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_text(revision + "\n")


setup(cmdclass={"build_py": BuildWithRevision})
