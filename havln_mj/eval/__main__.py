"""``python -m havln_mj.eval`` (see :mod:`havln_mj.eval.run`)."""

import sys

from havln_mj.eval.run import main

sys.exit(main())
