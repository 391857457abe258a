"""Writing results: the JSON Lines environment model."""
