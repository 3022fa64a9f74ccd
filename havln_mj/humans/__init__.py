"""People in the scene (filled by the humans issue)."""
