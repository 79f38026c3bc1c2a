"""Where every number of our results in a page comes from: ``unsourced(page)`` lists the table cells whose numbers
are not in a results file their section names (the docs build fails on any, ``docs/hooks.py``; so does
``tests/test_numbers.py`` for ``studies/README.md`` and ``docs/*.md`` as written).

The results files (``studies/*/results/``, ``benchmarks/results/``) are written by the scripts that measured
them; a table's number is looked up, to the digits it is printed with, among the numbers of the results files its
section names (a script ``li2022/one_year.py`` names ``li2022/results/one_year*``, a path ``.../results/x.md``
names itself), and every number of a cell must be in one and the same file, or in the files the cell itself
names.  Columns that hold a paper's claims (the header names the paper, "paper" or "claim") are not ours and are
skipped; so are the agree/differ columns' derived percentages.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
NUMBER = re.compile(r"(?<![\w.])[−+-]?\d+(?:\.\d+)?(?:e[−+-]?\d+)?")
THEIRS = re.compile(r"paper|claim|published|expected|agree|cause|note|Li 2022|Katz|Ye 2022|Gazzino|Ma &|figure|what", re.I)


def parse(token: str) -> float:
    return float(token.replace("−", "-"))


def half_unit(token: str) -> float:
    """Half a unit in the last printed digit of ``token`` ("0.0062" -> 5e-5, "4e-8" -> 5e-9)."""
    mantissa, _, exponent = token.replace("−", "-").partition("e")
    digits = len(mantissa.split(".")[1]) if "." in mantissa else 0
    return 0.5 * 10.0 ** (int(exponent or 0) - digits)


def results_files(section: str) -> list[Path]:
    found = set()
    for name in re.findall(r"([\w/\-]+\.py|[\w/\-]+/results/[\w.\-/]+\.(?:md|json))", section):
        for path in [ROOT / name, ROOT / "studies" / name, *(ROOT / "studies").glob(f"*/{name}")]:
            if path.is_file() and path.suffix == ".py":
                found |= {f for f in (path.parent / "results").glob(f"{path.stem}*")
                          if f.is_file() and f.suffix in (".md", ".json")}
            elif path.is_file() and path.suffix in (".md", ".json"):
                found.add(path)
    return sorted(found)


def our_cells(section: str):
    """(row label, cell) of every table cell of ours in ``section``."""
    header = None
    for line in section.splitlines():
        if not line.startswith("|"):
            header = None
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if header is None:
            header = cells
        elif not re.fullmatch(r"\|[\s:|-]+\|?", line.strip()):
            for title, cell in zip(header[1:], cells[1:]):
                if not THEIRS.search(title) or re.search(r"geojax|ours", title, re.I):
                    yield cells[0], cell


def found_in(tokens: list[str], numbers: list[float]) -> bool:
    return all(any(abs(abs(k) - abs(parse(t))) <= half_unit(t) * (1 + 1e-9) for k in numbers) for t in tokens)


def unsourced(text: str, label: str) -> list[str]:
    """The cells of ours in ``text`` whose numbers are not all in one results file of their section."""
    misses = []
    for section in re.split(r"\n(?=#+ )", text):
        files = results_files(section)
        if not files or "|" not in section:
            continue
        numbers = [[parse(t) for t in NUMBER.findall(f.read_text(errors="ignore"))] for f in files]
        for row, cell in our_cells(section):
            tokens = NUMBER.findall(cell)
            named = [parse(t) for f in results_files(cell) for t in NUMBER.findall(f.read_text(errors="ignore"))]
            if tokens and not any(found_in(tokens, pool) for pool in [*numbers, named]):
                misses.append(f"{label}: row {row[:50]!r}: the numbers of {cell[:120]!r} are not all in any one of "
                              f"{', '.join(str(f.relative_to(ROOT)) for f in files)}")
    return misses
