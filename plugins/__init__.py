"""gearlab's built-in plugins. They register through the `gearlab` entry-point group,
exactly as a third-party package would (see docs/plugins.md)."""
