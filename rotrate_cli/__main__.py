"""``python -m rotrate_cli``: the same as the ``rotrate`` command."""

from rotrate_cli.cli import main

main()
