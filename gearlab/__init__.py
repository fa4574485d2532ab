"""gearlab: a hybrid gearbox condition-monitoring lab (physics model + transfer learning).

The Python API for notebooks (docs/api.md): load a gearbox description, simulate, import and
inspect a recording, diagnose the gap, fit and score a detector, run a scenario file and score
new recordings with a finished run.

    import gearlab
    data = gearlab.simulate("B-6-ch5", teeth=[1, 2], faults={"crack": [13]}, healthy=8)

Its names are resolved on first use (PEP 562 ``__getattr__``; they live in gearlab.notebook), so
``import gearlab`` loads no torch, numba or scipy.stats. The plugin authors' API is gearlab.api.
"""

__version__ = "0.1.0"

# Bumped whenever a change alters simulated numbers; part of every dataset cache key.
PHYSICS_VERSION = "2"

# The notebook API: name -> the module that holds it, imported on first access (start-up time)
_API = dict.fromkeys(
    (
        "load_gearbox",
        "gearbox_orders",
        "simulate",
        "simulate_signals",
        "read_recording",
        "import_recording",
        "inspect_recording",
        "diagnose_gap",
        "corrected_source",
        "fit_detector",
        "detector_scores",
        "score_detector",
        "load_scenario",
        "validate_scenario",
        "run_scenario",
        "open_run",
        "run_verdict",
        "score_recordings",
    ),
    "gearlab.notebook",
)

__all__ = ["PHYSICS_VERSION", "__version__", *_API]


def __getattr__(name: str):
    if name in _API:
        import importlib

        return getattr(importlib.import_module(_API[name]), name)
    raise AttributeError(f"module 'gearlab' has no attribute '{name}'")


def __dir__() -> list[str]:
    return sorted({*globals(), *_API})
