"""Learning agents (filled by the agents issue; optional extra)."""
