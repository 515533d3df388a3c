"""`python -m plotbridge` is the `plotbridge` command."""

import sys

from plotbridge.cli import main

sys.exit(main())
