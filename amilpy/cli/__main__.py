"""`python -m amilpy.cli`: the command line, as the `amilpy` script runs it."""

import sys

from . import main

sys.exit(main())
