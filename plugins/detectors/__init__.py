"""Built-in detector plugins (beyond the thesis; no network): matched_filter and likelihood_ratio,
the simulator's fault shapes referenced and thresholded on the target's healthy history."""
