"""The afford command line (python -m afford)."""
from afford.interrupt import main

main()
