"""Where the project's shared folder lies: beside the repository (CI clones it there)."""

from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
#: ``shared/`` beside the clone: the paper, FORMATS.md and the samples.
SHARED = REPO.parent / "shared"
#: Real images with ground truth (research-use licences: read in place, never copied).
REAL_SAMPLES = SHARED / "samples" / "real"
