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
