"""A run's results in other tools' formats: CCSDS OEM (``trajectory``), OPM of the burns (``maneuvers``), a burn list."""
