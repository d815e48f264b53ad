"""``python -m amb_fast``: the ``amb-fast`` command."""

import sys

from .cli import main

sys.exit(main())
