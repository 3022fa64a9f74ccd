"""Evaluation harness (filled by the benchmark issue)."""
