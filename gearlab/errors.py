"""Errors that the CLI turns into one clear line and exit code 2."""


class GearlabInputError(Exception):
    """Bad input from the user: a scenario, a CLI option, a data file, a plugin parameter.

    The message is one line that says what is wrong, where (file, table, key) and what
    was expected. The CLI prints it and exits with code 2; nothing is half-written.
    """


class UnknownPluginError(GearlabInputError):
    """A plugin name that no registered plugin of that kind carries."""
