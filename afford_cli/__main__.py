"""The afford command line (python -m afford_cli)."""
from afford_cli.app import main

main()
