"""The user's own recordings in: image folders and videos with a calibration YAML and an
ego-pose CSV, manifests of many recordings, and converters from public datasets to that form."""
