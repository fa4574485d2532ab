"""Sim-to-real gap diagnosis (docs/gap.md): where source and target healthy data differ, and how far.

``views``: feature views of angle-domain revolutions (order bands, TSA residual per sector,
waveform statistics, network latent features); ``stats``: per-view discrepancies, their
shares of the total with bootstrap intervals, and the two-sample tests (classifier AUC,
MMD with a permutation p-value), gathered by :func:`gearlab.gap.stats.gap_report`.
See docs/gap_stats.md.
"""
