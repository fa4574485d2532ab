"""gearlab: a hybrid gearbox condition-monitoring lab (physics model + transfer learning)."""

__version__ = "0.1.0"

# Bumped whenever a change alters simulated numbers; part of every dataset cache key.
PHYSICS_VERSION = "1"
