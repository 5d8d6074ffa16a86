"""``python -m facemech``: the command line."""

from .cli import main

main()
