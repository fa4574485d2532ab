"""Issue 41, the gap verdict's wording: a gap whose permutation test passes alpha but whose
classifier tells the sets apart no better than chance is not significant (gearlab.gap.conclusion.
gap_seen); the verdict said 'no longer significant (p = 0.0476)' with nothing more, a p under
0.05 (tests/tui_scenarios/tgap.toml's report). It says why."""

from gearlab.kinds.gap_verdict import gap_lines

SUMMARY = {
    "gap_before": 4.88e6,
    "gap_after": 1952.0,
    "p_before": 0.0476,
    "p_after": 0.0476,
    "auc_before": 0.5,
    "auc_after": 0.5,
    "shrink": 1.0,
    "significant_before": True,
    "significant_after": False,
    "settings": {"alpha": 0.05},
    "views": {"tsa_residual": {"share_before": 0.95}},
    "effects": [{"name": "sensor_noise", "share_removed": 0.999, "round": 1, "params": {"snr_db": 4.4}}],
    "verdict": "explained",
}


def test_a_p_under_alpha_called_not_significant_says_the_classifier_is_at_chance():
    text = " ".join(gap_lines(SUMMARY))
    assert "no longer significant (p = 0.0476; the classifier's AUC 0.50 is within chance)" in text
    assert "differ significantly (gap 4.88e+06, p = 0.0476)" in text  # a significant gap: its p alone


def test_a_p_over_alpha_is_said_alone():
    text = " ".join(gap_lines({**SUMMARY, "p_after": 0.4}))
    assert "no longer significant (p = 0.4)" in text
