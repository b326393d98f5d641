"""``python -m csjm_opt.cli``: run the ``csjm`` command line."""

import sys

from .app import main

sys.exit(main())
