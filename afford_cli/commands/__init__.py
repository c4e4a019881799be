"""One thin module per subcommand: parse, call the library, format."""
