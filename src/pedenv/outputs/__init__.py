"""What a run writes out: the environment model as JSON Lines, Parquet, Rerun and MCAP,
``detections.json`` of ``pedenv detect``, and the output folder's own rules."""
