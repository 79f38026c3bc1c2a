"""The runner: from scenarios to the engine's arguments (``setup``: the controller, each sample's ``Params``,
the shared environment and reference), one or many rollouts compiled and run (``rollout``: ``simulate``,
``simulate_batch``, ``Result``), and a run's files, figures and summary (``report``).  The engine it runs,
``geojax.loop``, writes no file and draws no figure."""
