"""``python -m havln_mj <command>``: the ``havln_mj`` command (see :mod:`havln_mj.cli`)."""

import sys

from havln_mj.cli import main

sys.exit(main())
