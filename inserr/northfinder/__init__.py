"""northfinder."""
