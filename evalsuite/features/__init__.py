"""Speech features as the reference gesture generators compute them (recipes by name; in progress)."""
