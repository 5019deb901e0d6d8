"""Command-line interface: ``inserr <command>``; one module per command, imported lazily."""
