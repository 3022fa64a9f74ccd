"""``python -m havln_mj.eval`` (see :mod:`havln_mj.commands.evaluate`)."""

import sys

from havln_mj.commands.evaluate import main

sys.exit(main())
