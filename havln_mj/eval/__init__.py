"""Evaluation harness: scores agents and experts on HA-R2R and procedural splits."""
