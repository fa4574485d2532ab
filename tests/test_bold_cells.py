"""Issue 41: a Markdown table's bold cell (the gap benchmark's '**all** (12 trials)' row) reads
bold in report.html and in the TUI's results table, not with its asterisks."""

from gearlab.report import markdown_table

TABLE = "| effect | trials |\n|---|---|\n| sensor_noise | 1 |\n| **all** (1 trials) | 1 |\n"


def test_the_report_draws_a_bold_cell_bold():
    page = markdown_table(TABLE)
    assert "<td><b>all</b> (1 trials)</td>" in page and "**" not in page
    assert "<td>a &lt;b&gt; * c</td>" in markdown_table("| x |\n|---|\n| a <b> * c |\n")  # the rest stays text


def test_the_tuis_results_table_draws_a_bold_cell_bold():
    from gearlab.tui.widgets import cell

    shown = cell("**all** (1 trials)")
    assert shown.plain == "all (1 trials)" and any("bold" in str(span.style) for span in shown.spans)
    assert cell("[b]x[/b] *y*").plain == "[b]x[/b] *y*"  # data, not markup
