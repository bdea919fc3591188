"""``python -m cayley_heyoka.cli``: the ``cayley-heyoka`` command."""

import sys

from . import main

sys.exit(main())
