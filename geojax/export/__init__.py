"""A run's results in other tools' formats: CCSDS Orbit Ephemeris Messages and a burn list (``trajectory``)."""
