"""Procedural houses: ``proc-<seed>`` buildings written as scan folders."""
