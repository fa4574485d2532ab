"""Learning: networks, adapter contract and losses, training loops, protocol runners (thesis chapters 3-5).

- :mod:`gearlab.learn.networks` — networks by name (``cnn3``, ``fast``), each split into
  a feature extractor and a classifier so that adapters can act on the latent space.
- :mod:`gearlab.learn.adapters` — the :class:`~gearlab.learn.adapters.Adapter` contract
  that adapter plugins implement. It does not import torch: every ``gearlab`` command loads
  the adapter plugins through the registry, and most never train a network.
- :mod:`gearlab.learn.losses` — the shared torch losses (MMD², gradient reversal, CORAL).
- :mod:`gearlab.learn.training`, :mod:`gearlab.learn.protocol`, :mod:`gearlab.learn.noise_study`
  — training loops and the chapter-5 and chapter-4 protocols.

Import from the submodules; this package imports nothing, so that importing it stays cheap.
"""
