"""Scans: procedural houses, scan folders, navigation graphs, regions and collision geometry."""
