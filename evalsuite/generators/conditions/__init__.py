"""Built-in conditions: operators over the corpus's natural motion or any other condition (see
``docs/generators.md`` § Built-in conditions)."""
