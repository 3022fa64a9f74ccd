"""havln_mj: a MuJoCo simulator and benchmark for Human-Aware Vision-and-Language Navigation."""

__version__ = "0.1.0"
