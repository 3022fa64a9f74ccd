"""Runtime: world building and the simulator."""
