"""Output: atomic writes, report headers (environment), figures."""
