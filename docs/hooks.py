"""MkDocs hook: the parts of the pages that are made from the code, at build time, so they cannot drift.

A page asks for one with a line of its own, ``<!-- generated: NAME -->``, or ``<!-- include: PATH -->`` for a file
of the repository (``studies/README.md``) inlined as it is.  The generated parts:

* ``scenario-keys``: every table and key of a scenario file from ``geojax.scenario_schema.SCHEMA`` (the ``Field``
  declarations the loader validates with): type, default, allowed range or choices, the ``Params`` leaf it becomes
  and whether ``geojax tune`` can move it;
* ``controller-keys``: the ``[controller]`` keys of every registered controller, from each module's ``FIELDS``;
* ``tuning-keys``: the keys of a tuning file, from ``geojax.tune.FIELDS``, each with its one-line meaning;
* ``metrics``: the names, units and meanings of the results files' datasets (``geojax.results``);
* ``cli-help``: ``geojax --help`` and every command's ``--help``, as the installed command prints them;
* ``scenarios``: the shipped scenarios with their descriptions;
* ``modules-geojax``, ``modules-studies``, ``modules-benchmarks``: every file of the folder with the first
  paragraph of its docstring.

An unknown name or a missing file fails the build (``mkdocs build --strict`` in the tests), and so does a number
of ours in a page's tables that no results file of its section holds (``docs/number_sources.py``): the pages'
numbers are checked by the build against the files the scripts wrote.
"""

from __future__ import annotations

import contextlib
import importlib.util
import io
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MARKER = re.compile(r"^<!-- (generated|include): (\S+) -->$", re.M)


def on_page_markdown(markdown: str, page, config, files) -> str:
    where = page.file.src_path
    # The tables as written (the page and the files it includes; the generated parts come from the code) hold no
    # number of ours that their results files do not.
    written = MARKER.sub(lambda m: _expand(m.group(1), m.group(2), where) if m.group(1) == "include" else "", markdown)
    misses = _number_sources().unsourced(written, where)
    if misses:
        raise ValueError("numbers without a results file:\n" + "\n".join(misses))
    return MARKER.sub(lambda m: _expand(m.group(1), m.group(2), where), markdown)


def _number_sources():
    """``docs/number_sources.py``, loaded by path (the docs folder is not a package)."""
    spec = importlib.util.spec_from_file_location("number_sources", Path(__file__).with_name("number_sources.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _expand(kind: str, name: str, where: str) -> str:
    if kind == "include":
        path = ROOT / name
        if not path.is_file():
            raise ValueError(f"{where}: include of {name}: no such file")
        return path.read_text()
    if name not in GENERATORS:
        raise ValueError(f"{where}: no generated part named {name!r}; known: {', '.join(GENERATORS)}")
    return GENERATORS[name]()


def _cell(text) -> str:
    return str(text).replace("|", "\\|")


def _kind(field) -> str:
    kinds = field.kind if isinstance(field.kind, tuple) else (field.kind,)
    names = {int: "integer", float: "number", bool: "true/false", str: "string", list: "list"}
    return " or ".join(dict.fromkeys(names.get(k, k.__name__) for k in kinds))


def _default(field) -> str:
    from geojax.params import REQUIRED

    if field.default is REQUIRED:
        return "**required**"
    return "—" if field.default is None else f"`{field.default!r}`"


def _field_rows(table: str, fields: dict) -> list[str]:
    rows = []
    for key, field in fields.items():
        dotted = f"{table}.{key}" if table else key
        leaf = f"`{field.si}`" if field.si else ""
        tunable = field.transform.name if field.transform else ""
        tunable += f" (alias `{field.alias}`)" if field.transform and field.alias else ""
        static = " (static: not sweepable)" if field.static else ""
        rows.append(f"| `{dotted}` | {_kind(field)} | {_default(field)} | {_cell(field.describe())}{static} | "
                    f"{leaf} | {tunable} |")
    return rows


HEADER = ["| key | type | default | allowed | Params leaf (SI) | tunable |", "|---|---|---|---|---|---|"]


def scenario_keys() -> str:
    from geojax.scenario_schema import SCHEMA

    out = []
    for table, fields in SCHEMA.items():
        out += [f"### `[{table}]`" if table else "### Top level", "", *HEADER, *_field_rows(table, fields), ""]
    return "\n".join(out)


def controller_keys() -> str:
    from geojax.control import REGISTRY, lookup

    out = []
    for name in REGISTRY:
        module = lookup(name)
        fields = dict(module.FIELDS)
        doc = (module.__doc__ or "").strip().split("\n\n")[0].replace("\n", " ")
        out += [f"### `kind = \"{name}\"`", "", doc, ""]
        out += [*HEADER, *_field_rows("controller", fields), ""] if fields else ["No keys of its own.", ""]
    return "\n".join(out)


def tuning_keys() -> str:
    from geojax.tune import FIELDS

    rows = ["| key | type | default | allowed | meaning |", "|---|---|---|---|---|"]
    for key, field in FIELDS.items():
        rows.append(f"| `{key}` | {_kind(field)} | {_default(field)} | {_cell(field.describe())} | {_cell(field.doc)} |")
    return "\n".join(rows)


def metrics() -> str:
    from geojax.results import DESCRIPTIONS, units_of

    rows = ["| dataset | unit | meaning |", "|---|---|---|"]
    for name, text in DESCRIPTIONS.items():
        if re.fullmatch(r"dv_year\d+_mps", name) and name != "dv_year1_mps":
            continue
        shown = "dv_year<k>_mps" if name == "dv_year1_mps" else name
        meaning = text.replace("year 1 ", "year k ") if name == "dv_year1_mps" else text
        rows.append(f"| `{shown}` | {units_of(name) or '1'} | {_cell(meaning)} |")
    return "\n".join(rows)


def cli_help() -> str:
    from geojax import cli

    parser = cli._parser()
    commands = [a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction"][0].choices
    out = ["```text", "$ geojax --help", parser.format_help().rstrip(), "```", ""]
    for name, sub in commands.items():
        out += [f"### `geojax {name}`", "", "```text", sub.format_help().rstrip(), "```", ""]
    return "\n".join(out)


def scenarios() -> str:
    from geojax import scenario

    rows = ["| name | description |", "|---|---|"]
    for name in scenario.available():
        with contextlib.redirect_stderr(io.StringIO()):
            description = scenario.load(name).config.get("description", "")
        rows.append(f"| `{name}` | {_cell(description)} |")
    return "\n".join(rows)


def _first_line(path: Path) -> str:
    import ast

    doc = ast.get_docstring(ast.parse(path.read_text())) or ""
    return doc.strip().split("\n\n")[0].replace("\n", " ")


def modules(folder: str) -> str:
    """One row per Python file under ``folder`` (a package or a folder of scripts): its docstring's first paragraph."""
    rows = ["| file | what it is |", "|---|---|"]
    for path in sorted((ROOT / folder).rglob("*.py")):
        if path.name == "__main__.py" or "data" in path.relative_to(ROOT).parts[1:-1]:
            continue
        rows.append(f"| `{path.relative_to(ROOT)}` | {_cell(_first_line(path))} |")
    return "\n".join(rows)


GENERATORS = {"scenario-keys": scenario_keys, "controller-keys": controller_keys, "tuning-keys": tuning_keys,
              "metrics": metrics,
              "cli-help": cli_help, "scenarios": scenarios,
              **{f"modules-{name}": (lambda name=name: modules(name)) for name in ("geojax", "studies", "benchmarks")}}
