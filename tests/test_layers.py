"""The package's layers, as docs/design.md and docs/layout.md list them: imports point down only, the engine and
everything below it import no file, figure, export, result, command line, sweep or tuning, and the two pages hold
one list.

Independent check: every import statement of every module, module-level and deferred alike, read from the
source with ``ast`` (not from what a run happens to import).
"""

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "geojax"
# The engine and what it stands on (layers 1-5 of docs/design.md).
BELOW_THE_RUNNER = ("geojax/physics", "geojax/params.py", "geojax/nominal_errors.py", "geojax/reductions.py", "geojax/per_lane.py",
                    "geojax/control", "geojax/states", "geojax/navigation", "geojax/loop")
# What the runner and orchestration own: files, figures, exports, results, the command line, sweeps, tuning.
ABOVE = ("geojax.runner", "geojax.export", "geojax.plots", "geojax.figures", "geojax.store", "geojax.results",
         "geojax.cli", "geojax.cli_args", "geojax.sweep", "geojax.tune", "geojax.progress", "geojax.compilation",
         "geojax.traced", "geojax.bound", "geojax.transfer", "geojax.uncontrolled")


def _imports(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
            names.update(f"{node.module}.{a.name}" for a in node.names)
    return names


def test_the_engine_and_below_import_no_file_figure_cli_sweep_or_tuning():
    offenders = []
    for path in sorted(PACKAGE.rglob("*.py")):
        where = path.relative_to(ROOT).as_posix()
        if not where.startswith(BELOW_THE_RUNNER):
            continue
        for name in _imports(path):
            if name.startswith(ABOVE) and not name.startswith("geojax.runner_"):
                offenders.append(f"{where}: {name}")
    assert not offenders, offenders


def test_the_schema_imports_no_controller_no_part_and_no_loop():
    names = _imports(PACKAGE / "scenario_schema.py")
    assert not [n for n in names if n.startswith(("geojax.control", "geojax.states", "geojax.loop", "geojax.runner",
                                                    "geojax.navigation"))], names


def _layers(page: str) -> list[str]:
    text = (ROOT / "docs" / page).read_text()
    block = text.split("<!-- layers -->", 2)[1]
    return [line for line in block.splitlines() if line.strip()]


def test_design_and_layout_list_the_same_layers():
    design, layout = _layers("design.md"), _layers("layout.md")
    assert design == layout and len([l for l in design if re.match(r"\d\. ", l)]) == 7


def test_the_code_cites_pages_that_exist():
    missing = []
    for path in sorted(PACKAGE.rglob("*.py")):
        text = path.read_text()
        if "DESIGN.md" in text:
            missing.append(f"{path.relative_to(ROOT)}: DESIGN.md (not in a user's clone)")
        for page in re.findall(r"docs/([\w-]+\.md)", text):
            if not (ROOT / "docs" / page).exists():
                missing.append(f"{path.relative_to(ROOT)}: docs/{page}")
    assert not missing, missing
