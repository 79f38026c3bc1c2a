"""The closed loop (DESIGN.md layer 5): one ``simulate`` for every controller, its records, metrics and status."""
