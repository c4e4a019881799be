"""The afford command line (python -m afford)."""
from afford.app import main

main()
