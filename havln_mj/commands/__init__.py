"""The ``havln_mj`` command's own subcommands (the others live with what they run)."""
