"""Pictures on camera images: skeletons, track ids and distances drawn over the frames."""
