"""havln_mj: a MuJoCo simulator and benchmark for Human-Aware Vision-and-Language Navigation."""

__version__ = "0.1.0"

# The simulator API at the top level, so MatterSim code runs with `import havln_mj as MatterSim`.
# Imported lazily: `import havln_mj.errors` stays light.
_API = {
    "Simulator": "havln_mj.sim.simulator",
    "SimState": "havln_mj.sim.state",
    "ViewPoint": "havln_mj.sim.state",
    "EgoAction": "havln_mj.sim.egocentric",
}


def __getattr__(name: str) -> object:
    module = _API.get(name)
    if module is None:
        raise AttributeError(f"module 'havln_mj' has no attribute {name!r}")
    import importlib

    return getattr(importlib.import_module(module), name)
