"""Built-in adapter plugins (thesis ch. 5): source_only, target_only, mmd, dann; beyond the
seed, coral and finetune (Han et al. 2019b). Methods without a network are detectors (plugins/detectors)."""
