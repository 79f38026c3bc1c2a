"""The documentation builds with every warning an error (a broken link or anchor, a missing page, an unknown
generated part), its generated parts hold what the code declares, committed as the code makes them now, and
every link and file path the pages give resolves inside the repository (a clone is all its reader has)."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")), *sorted((ROOT / "studies").rglob("README.md"))]


def _docs_module(name: str):
    sys.path.insert(0, str(ROOT / "docs"))
    try:
        return __import__(name)
    finally:
        sys.path.remove(str(ROOT / "docs"))


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
    hooks = _docs_module("hooks")
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

    hooks = _docs_module("hooks")
    page = SimpleNamespace(file=SimpleNamespace(src_path="page.md"))
    source = "studies/li2022/results/uncontrolled_year.md"
    number = next(n for n in hooks._number_sources().NUMBER.findall((ROOT / source).read_text()) if len(n) >= 6)
    table = f"## A section\n\nFrom `{source}`:\n\n| case | geojax |\n|---|---|\n| row | {number} |\n"
    assert hooks.on_page_markdown(table, page, None, None) == table
    with pytest.raises(ValueError, match="numbers without a results file"):
        hooks.on_page_markdown(table.replace(number, "123.456789"), page, None, None)


def test_the_committed_generated_parts_are_what_the_code_makes():
    """The pages read on disk hold the tables the site shows: every ``<!-- generated: NAME -->`` part of
    ``docs/*.md`` is what ``docs/generate.py`` writes from the code now (a key, option or metric added to the code
    fails here until the pages are regenerated)."""
    generate = _docs_module("generate")
    stale = [str(page.relative_to(ROOT)) for page in generate.stale()]
    assert not stale, f"generated parts out of date in {', '.join(stale)}: run `{generate.COMMAND}` and commit"


def test_a_generated_part_without_its_end_line_is_refused():
    hooks = _docs_module("hooks")
    page = "# A page\n\n<!-- generated: scenarios -->\n\n| a | b |\n"
    with pytest.raises(ValueError, match="without its '<!-- end"):
        hooks.fill(page, "page.md")


def _links(text: str):
    """The relative targets of the Markdown links in ``text`` (no scheme, not a bare ``#anchor``), anchor cut."""
    for target in re.findall(r"\]\(([^)\s]+)\)", text):
        if not re.match(r"[a-z][\w+.-]*:|#", target):
            yield target.split("#")[0]


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_link_and_named_file_resolves_inside_the_repository(page):
    """Every relative link of README.md, docs/*.md and studies/**/README.md is a file or folder of the repository
    (none escapes its root), every file path named in backticks exists (looked up from the root, the page's folder,
    ``geojax/`` and the studies' folders, as the pages write them; NAME-like placeholders skipped), and no page
    points at the folders beside the repository (``../shared``) or cites an issue ("issue 32"), which a clone's
    reader cannot open."""
    text = page.read_text()
    assert "../shared" not in text
    assert not re.search(r"\bissues? \d", text, re.I), re.search(r".*\bissues? \d.*", text, re.I).group(0)[:200]
    misses = []
    for target in _links(text):
        path = (page.parent / target).resolve()
        if not path.is_relative_to(ROOT) or not path.exists():
            misses.append(f"link {target}")
    for named in re.findall(r"(?<!\[)`([\w./-]+/[\w.-]+\.(?:py|toml|md|json))`", text):
        if re.search(r"[A-Z]{3,}", named):
            continue
        where = [ROOT, page.parent, ROOT / "geojax", ROOT / "studies", *(ROOT / "studies").iterdir()]
        if not any((base / named).resolve().is_relative_to(ROOT) and (base / named).is_file() for base in where):
            misses.append(f"file {named}")
    assert not misses, f"{page.relative_to(ROOT)}: " + "; ".join(misses)


def test_the_momentum_page_names_every_shipped_scenario_that_carries_wheels():
    """docs/momentum.md says which shipped scenarios turn the wheels on; the scenarios themselves say which do."""
    from geojax import scenario

    with_wheels = {name for name in scenario.available()
                   if scenario.load(name).config.get("attitude", {}).get("wheels")}
    page = " ".join((ROOT / "docs" / "momentum.md").read_text().split())
    sentence = re.search(r"with `wheels = false` \(every shipped scenario but (.+?)\)", page)
    assert sentence and set(re.findall(r"`([\w-]+)`", sentence.group(1))) == with_wheels


def test_a_starting_points_description_says_what_it_flies():
    """A shipped scenario without station keeping but with the recovery law says so; one with neither says it is
    uncontrolled (a description that says "uncontrolled" of a scenario that burns would mislead)."""
    from geojax import scenario

    for name in scenario.available():
        config = scenario.load(name).config
        if config.get("controller", {}).get("kind", "none") != "none":
            continue
        description = config["description"]
        if config["controller"].get("recovery"):
            assert "recovery law" in description and "uncontrolled" not in description, name
        else:
            assert "recovery" not in description, name


# Options every command (or every command that writes a file, or the four that take it) has, said once for all
# in docs/commands.md's prose rather than in each command's line of its first table.
_SAID_FOR_ALL = {"--quiet": "`-q`", "--verbose": "`-v`", "--no-cache": "`--no-cache` on any command",
                 "--force": "`--force` is given (every command that writes one", "--set": "**`--set KEY=VALUE`**"}


def test_each_commands_line_in_the_commands_page_names_its_parsers_options():
    """docs/commands.md's first table (hand-written: what each command is for) has a line for every command of
    the parser, and each line's usage names exactly that command's options (second method: argparse's own
    parser, what ``--help`` prints), but for those the page says once for all; the ``--set`` paragraph names the
    commands that take it.  The table under "Every command's options" is generated from the same parser."""
    import argparse

    from geojax import cli

    page = (ROOT / "docs" / "commands.md").read_text()
    prose = " ".join(page.split("<!-- generated: cli-help -->")[0].split())
    table = page.split("\n\n")[1].splitlines()
    sub = next(a for a in cli._parser()._actions if isinstance(a, argparse._SubParsersAction))
    with_set = set()
    for name, parser in sub.choices.items():
        options = {o for a in parser._actions for o in a.option_strings if o.startswith("--")} - {"--help"}
        usages = [line.split("` |")[0] for line in table if line.startswith(f"| `geojax {name} ")]
        assert usages, f"docs/commands.md: no line for `geojax {name}`"
        named = {o for usage in usages for o in re.findall(r"--[a-z][a-z0-9-]*", usage)}
        assert named <= options, f"geojax {name}: the page names {sorted(named - options)}, which it does not take"
        missing = options - named - set(_SAID_FOR_ALL)
        assert not missing, f"geojax {name}: its line in docs/commands.md lacks {sorted(missing)}"
        with_set |= {name} if "--set" in options else set()
    for option, words in _SAID_FOR_ALL.items():
        assert words in prose, f"docs/commands.md: {option} is not said for every command ({words!r})"
    said = re.search(r"\*\*`--set KEY=VALUE`\*\* \(repeatable\) on (.+?) sets", prose)
    assert said and set(re.findall(r"`(\w+)`", said.group(1))) == with_set
