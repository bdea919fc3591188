"""``python -m cayley_heyoka``: the ``cayley-heyoka`` command."""

import sys

from .cli import main

sys.exit(main())
