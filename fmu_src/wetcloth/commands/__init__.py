"""Subcommands of the ``wetcloth`` command line, one module each."""
