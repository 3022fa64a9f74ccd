"""``python -m havln_mj.agents.train``."""

import sys

from havln_mj.agents.train.cli import main

sys.exit(main())
