"""The README's Python examples run as written (in a fresh folder, one after another, as a reader would)."""

import re
from pathlib import Path

README = Path(__file__).resolve().parent.parent / "README.md"


def python_examples() -> list[str]:
    section = README.read_text().split("\n## Python", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```python\n(.*?)```", section, flags=re.S)


def test_the_readme_python_examples_run_as_written(tmp_path, monkeypatch, capsys):
    """Each example in a namespace of its own (a reader copies one block; its files stay for the next)."""
    examples = python_examples()
    assert len(examples) >= 3  # a batch, a controller of one's own (simulate, sweep, tuning), reading results
    monkeypatch.chdir(tmp_path)
    for number, code in enumerate(examples, 1):
        namespace = {"__name__": "__readme__"}
        exec(compile(code, f"README.md, Python example {number}", "exec"), namespace)
        if number == 1:  # the batch stays in the box: every sample's status is 0, as its comment says
            assert capsys.readouterr().out.splitlines()[0] == "[100   0   0   0   0   0]"
    assert (tmp_path / "mine.h5").is_file()
    assert namespace["ds"].dv_per_year_mps.dims == ("controller", "controller.k_inc_per_s", "repetition")
