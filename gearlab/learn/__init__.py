"""Learning: the 1-D CNNs of thesis 3.1 and the domain-adaptation contract of chapter 5.

- :mod:`gearlab.learn.networks` — networks by name (``cnn3``, ``fast``), each split into
  a feature extractor and a classifier so that adapters can act on the latent space.
- :mod:`gearlab.learn.adapters` — the :class:`~gearlab.learn.adapters.Adapter` contract
  that adapter plugins implement, and the shared losses (MMD², gradient reversal, CORAL).
"""

from .adapters import Adapter, GradientReversal, coral_loss, grad_reverse, mmd2
from .networks import DEFAULT_NETWORK, NETWORKS, Network, build_network

__all__ = [
    "Adapter",
    "DEFAULT_NETWORK",
    "GradientReversal",
    "NETWORKS",
    "Network",
    "build_network",
    "coral_loss",
    "grad_reverse",
    "mmd2",
]
