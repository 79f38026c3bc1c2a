"""The parts of the pages that are made from the code, so they cannot drift: written into the pages by
``python docs/generate.py`` (committed, so the pages read on disk hold them) and filled afresh by this MkDocs hook
when the site is built.

A generated part sits between two lines of its own, ``<!-- generated: NAME -->`` and ``<!-- end generated: NAME
-->``; ``<!-- include: PATH -->`` ... ``<!-- end include: PATH -->`` holds a file of the repository
(``studies/README.md``) as it is.  The generated parts:

* ``scenario-keys``: every table and key of a scenario file from ``geojax.scenario.SCHEMA`` (the ``Field``
  declarations the loader validates with): type, default, allowed range or choices, the ``Params`` leaf it becomes
  and whether ``geojax tune`` can move it;
* ``controller-keys``: the ``[controller]`` keys of every registered controller, from each module's ``SPEC.fields``;
* ``tuning-keys``: the keys of a tuning file, from ``geojax.tune.FIELDS``, each with its one-line meaning;
* ``metrics``: the names, units and meanings of the results files' datasets (``geojax.results``);
* ``cli-help``: every command and option of ``geojax`` with its help, from the command's own parser;
* ``scenarios``: the shipped scenarios with their descriptions;
* ``api``: the names ``geojax`` exports, each with the first paragraph of its docstring;
* ``modules-geojax``, ``modules-studies``, ``modules-benchmarks``: every file of the folder with the first
  paragraph of its docstring.

An unknown name or a missing file fails the build (``mkdocs build --strict`` in the tests), and so does a number
of ours in a page's tables that no results file of its section holds (``docs/number_sources.py``): the pages'
numbers are checked by the build against the files the scripts wrote.  ``tests/test_docs.py`` fails when a
committed part is not what ``python docs/generate.py`` would write.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.util
import io
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BLOCK = re.compile(r"^<!-- (generated|include): (\S+) -->\n(.*?)^<!-- end \1: \2 -->$", re.M | re.S)


def on_page_markdown(markdown: str, page, config, files) -> str:
    where = page.file.src_path
    filled = fill(markdown, where)
    misses = _number_sources().unsourced(written(filled), where)
    if misses:
        raise ValueError("numbers without a results file:\n" + "\n".join(misses))
    return filled


def fill(markdown: str, where: str) -> str:
    """``markdown`` with every generated part and include made afresh from the code and the files."""
    def block(m):
        kind, name = m.group(1), m.group(2)
        return f"<!-- {kind}: {name} -->\n\n{_expand(kind, name, where).strip()}\n\n<!-- end {kind}: {name} -->"
    if len(re.findall(r"^<!-- (?:generated|include): ", markdown, re.M)) != len(BLOCK.findall(markdown)):
        raise ValueError(f"{where}: a generated part or include without its '<!-- end ... -->' line")
    return BLOCK.sub(block, markdown)


def written(markdown: str) -> str:
    """The page as written by hand (the files it includes kept, the generated parts, which come from the code,
    emptied): the text whose tables must hold no number of ours that their results files do not."""
    return BLOCK.sub(lambda m: m.group(0) if m.group(1) == "include" else "", markdown)


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
        static = " (static: sets the compiled program, one value per batch)" if field.static else ""
        rows.append(f"| `{dotted}` | {_kind(field)} | {_default(field)} | {_cell(field.describe())}{static} | "
                    f"{leaf} | {tunable} |")
    return rows


HEADER = ["| key | type | default | allowed | Params leaf (SI) | tunable |", "|---|---|---|---|---|---|"]


def scenario_keys() -> str:
    from geojax import scenario_cluster
    from geojax.scenario import SCHEMA  # the loop's tables, then each registered part's

    out = []
    for table, fields in SCHEMA.items():
        out += [f"### `[{table}]`" if table else "### Top level", "", *HEADER, *_field_rows(table, fields), ""]
    out += ["### `[collocation]` (a cluster's, with `[[satellites]]`: docs/collocation.md)", "", *HEADER,
            *_field_rows("collocation", scenario_cluster.FIELDS), ""]
    return "\n".join(out)


def navigation_keys() -> str:
    """The ``[navigation]`` keys and its sub-tables' (``geojax.navigation.keys``)."""
    from geojax.navigation import keys

    out = []
    for table, fields in (("navigation", keys.FIELDS), ("navigation.stations", keys.STATION_FIELDS),
                          ("navigation.gnss", keys.GNSS_FIELDS)):
        out += [f"### `[{'[' + table + ']' if table.endswith('stations') else table}]`", "", *HEADER,
                *_field_rows(table, fields), ""]
    return "\n".join(out)


def controller_keys() -> str:
    from geojax.control import REGISTRY, lookup

    out = []
    for name in REGISTRY:
        module = lookup(name)
        fields = dict(module.SPEC.fields)
        out += [f"### `kind = \"{name}\"`", "", _first_paragraph(module.__doc__), ""]
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
    """Every command and its arguments as tables (not argparse's ``--help`` text, whose layout changes with the
    Python version and the terminal's width)."""
    from geojax import cli

    parser = cli._parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    out = [f"`{parser.prog}`: {parser.description}", "", *_argument_rows(parser, skip=sub), ""]
    out += ["| command | what it does |", "|---|---|"]
    out += [f"| [`geojax {c.dest}`](#geojax-{c.dest}) | {_cell(c.help)} |" for c in sub._choices_actions]
    for choice in sub._choices_actions:
        out += ["", f"### `geojax {choice.dest}`", "", f"{choice.help}.", "", *_argument_rows(sub.choices[choice.dest])]
    return "\n".join(out)


def _argument_rows(parser, skip=None) -> list[str]:
    rows = ["| argument | meaning |", "|---|---|"]
    formatter = parser._get_formatter()
    for action in parser._actions:
        if action is skip or isinstance(action, argparse._HelpAction):
            continue
        if action.option_strings:
            value = ("{" + ",".join(action.choices) + "}" if action.choices else action.metavar or action.dest.upper())
            value = "" if action.nargs == 0 else f" [{value}]" if action.nargs == "?" else f" {value}"
            name = ", ".join(action.option_strings) + value
        else:
            name = action.metavar or action.dest.upper()
        required = " (required)" if action.option_strings and action.required else ""
        rows.append(f"| `{name}` | {_cell(formatter._expand_help(action))}{required} |")
    return rows


def scenarios() -> str:
    from geojax import scenario

    rows = ["| name | description |", "|---|---|"]
    for name in scenario.available():
        with contextlib.redirect_stderr(io.StringIO()):
            description = scenario.load(name).config.get("description", "")
        rows.append(f"| `{name}` | {_cell(description)} |")
    return "\n".join(rows)


def api() -> str:
    """One row per name ``geojax`` exports: a class or function with its docstring's first paragraph, a value
    with its type's (and, for a tuple of texts, the texts)."""
    import inspect

    import geojax

    rows = ["| name | what it is |", "|---|---|"]
    for name in geojax.__all__:
        obj = getattr(geojax, name)
        if inspect.isclass(obj) or inspect.isfunction(obj):
            kind, doc = ("class" if inspect.isclass(obj) else "function"), inspect.getdoc(obj)
        else:
            kind, doc = f"a `{type(obj).__name__}`", inspect.getdoc(type(obj))
            if isinstance(obj, tuple) and all(isinstance(x, str) for x in obj):
                doc = "; ".join(f"{i}: {x}" for i, x in enumerate(obj))
        rows.append(f"| `geojax.{name}` | {kind}: {_cell(_first_paragraph(doc))} |")
    return "\n".join(rows)


def _first_line(path: Path) -> str:
    import ast

    return _first_paragraph(ast.get_docstring(ast.parse(path.read_text())))


def _first_paragraph(doc: str | None) -> str:
    return (doc or "").strip().split("\n\n")[0].replace("\n", " ")


def modules(folder: str) -> str:
    """One row per Python file under ``folder`` (a package or a folder of scripts): its docstring's first paragraph."""
    rows = ["| file | what it is |", "|---|---|"]
    for path in sorted((ROOT / folder).rglob("*.py")):
        if path.name == "__main__.py" or "data" in path.relative_to(ROOT).parts[1:-1]:
            continue
        rows.append(f"| `{path.relative_to(ROOT)}` | {_cell(_first_line(path))} |")
    return "\n".join(rows)


GENERATORS = {"scenario-keys": scenario_keys, "controller-keys": controller_keys, "tuning-keys": tuning_keys,
              "navigation-keys": navigation_keys, "metrics": metrics,
              "cli-help": cli_help, "scenarios": scenarios, "api": api,
              **{f"modules-{name}": (lambda name=name: modules(name)) for name in ("geojax", "studies", "benchmarks")}}
