"""``python -m geojax``: the ``geojax`` command."""

import sys

from geojax.cli import main

sys.exit(main())
