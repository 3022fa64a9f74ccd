"""Gymnasium environments (filled by the gymnasium issue; optional extra)."""
