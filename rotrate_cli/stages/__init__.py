"""The pipeline stages (listed in pipeline order below)."""
