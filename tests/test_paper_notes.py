"""A shipped scenario that sets a paper's numbers beside its own, and flies a run that is not the paper's, says
how it differs (papers.DIFFERS_FROM_PAPER, printed in its summary)."""

from geojax import papers, scenario


def test_every_paper_scenario_that_departs_from_the_papers_run_has_a_note():
    for name in scenario.available():
        config = scenario.load(name).config
        published, _ = papers.published(name, config)
        base = papers.paper_run(name, config)
        if not published or base is None:
            continue
        assert base in scenario.available(), name
        changed = papers.departures(config, 0, scenario.load(base).config)
        if changed:
            assert papers.DIFFERS_FROM_PAPER.get(name, "").strip(), (name, changed[:3])
        else:
            assert name not in papers.DIFFERS_FROM_PAPER, name


def test_the_notes_name_shipped_scenarios():
    assert set(papers.DIFFERS_FROM_PAPER) <= set(scenario.available())
    assert {"li2022-qffc-ranging", "li2022-momentum"} <= set(papers.DIFFERS_FROM_PAPER)


def test_the_parts_the_readme_says_a_scenario_turns_on_are_on_and_no_others():
    """README: the wheels in li2022-momentum and li2022-momentum-mpc, the filter in li2022-qffc-ranging, and the
    thrusters' wear only with --set wear.enabled=true (no shipped scenario turns it on)."""
    from pathlib import Path

    readme = (Path(__file__).resolve().parent.parent / "README.md").read_text()
    wheels = {"li2022-momentum", "li2022-momentum-mpc"}
    navigation = {"li2022-qffc-ranging"}
    for name in wheels | navigation:
        assert f"`{name}`" in readme or f"geojax simulate {name}" in readme, name
    for name in scenario.available():
        config = scenario.load(name).config
        assert bool(config.get("attitude", {}).get("wheels")) == (name in wheels), name
        assert (config.get("navigation", {}).get("model", "none") == "ekf") == (name in navigation), name
        assert not config.get("wear", {}).get("enabled", False), name
