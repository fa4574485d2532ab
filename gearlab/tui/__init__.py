"""The Textual TUI (`gearlab tui`)."""

from .app import GearlabApp, run_tui

__all__ = ["GearlabApp", "run_tui"]
