"""`python -m gearlab`: the same as the `gearlab` command."""

from .cli import main

main()
