"""The command line: one module per command group; ``pneumaquad.cli.main:main`` is the
entry point."""
