"""afford_cli: the command line, the only package that touches files or the terminal."""
