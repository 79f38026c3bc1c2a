"""The documentation builds with every warning an error (a broken link or anchor, a missing page, an unknown
generated part), and its generated parts hold what the code declares."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_the_documentation_builds_strict(tmp_path):
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    keys = (tmp_path / "site" / "scenario-keys" / "index.html").read_text()
    assert "thrusters.beta_max_deg" in keys and "forces.gravity_degree" in keys
    assert "geojax sweep" in (tmp_path / "site" / "commands" / "index.html").read_text()


def test_the_generated_tables_follow_the_code():
    """Every scenario key and every controller key appears once in the generated tables (a key added to the
    schema appears without touching the pages)."""
    sys.path.insert(0, str(ROOT / "docs"))
    try:
        import hooks
    finally:
        sys.path.remove(str(ROOT / "docs"))
    from geojax.control import REGISTRY, lookup
    from geojax.scenario import SCHEMA

    text = hooks.scenario_keys()
    for table, fields in SCHEMA.items():
        for key in fields:
            assert f"| `{table + '.' if table else ''}{key}` |" in text
    controllers = hooks.controller_keys()
    for name in REGISTRY:
        assert f'kind = "{name}"' in controllers
        for key in lookup(name).FIELDS:
            assert f"| `controller.{key}` |" in controllers


def test_the_build_refuses_a_number_of_ours_that_no_results_file_holds():
    """The build checks the tables as written (``docs/number_sources.py``): a cell copied from the results file
    its section names renders; the same cell with a number no file holds fails the build."""
    from types import SimpleNamespace

    import pytest

    sys.path.insert(0, str(ROOT / "docs"))
    try:
        import hooks
    finally:
        sys.path.remove(str(ROOT / "docs"))
    page = SimpleNamespace(file=SimpleNamespace(src_path="page.md"))
    source = "studies/li2022/results/uncontrolled_year.md"
    number = next(n for n in hooks._number_sources().NUMBER.findall((ROOT / source).read_text()) if len(n) >= 6)
    table = f"## A section\n\nFrom `{source}`:\n\n| case | geojax |\n|---|---|\n| row | {number} |\n"
    assert hooks.on_page_markdown(table, page, None, None) == table
    with pytest.raises(ValueError, match="numbers without a results file"):
        hooks.on_page_markdown(table.replace(number, "123.456789"), page, None, None)
