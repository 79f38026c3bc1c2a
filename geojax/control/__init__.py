"""Station-keeping controllers (DESIGN.md layer 4); one module per idea."""
