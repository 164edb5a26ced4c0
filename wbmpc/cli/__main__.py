"""``python -m wbmpc.cli``: the ``wbmpc`` command line."""

import sys

from wbmpc.cli import main

sys.exit(main())
