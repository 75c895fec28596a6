"""Subcommands of the ``upm`` command line (see :mod:`upm.cli`)."""
