"""Test-session settings shared by every test module."""
import os

from hypothesis import settings

# The study-server tests' fixtures (study folder, SQLite and PostgreSQL database URLs).
pytest_plugins = ["study_fixtures"]

# On CI the property tests run a fixed set of examples (same seed every run) and keep no example
# database, so a red build always reproduces; locally they explore new examples each run.
settings.register_profile("ci", derandomize=True, database=None, print_blob=True)
if os.environ.get("CI"):
    settings.load_profile("ci")
