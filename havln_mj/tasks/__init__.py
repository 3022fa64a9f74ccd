"""Task layer: episodes, experts and metrics (filled by the benchmark issue)."""
