"""``python -m pedenv`` runs the command line."""

from pedenv.cli import main

main()
