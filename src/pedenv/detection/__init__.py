"""Detection: how the pose network's passes are spent on a frame (the modes ``fast``, ``far``, ``stream``).

``pose/`` is the network (one pass over an image, and raw runs of inputs); this package decides
where it looks. :func:`create_detector` picks the mode (:mod:`pedenv.detection.detector`); the
settings are :mod:`pedenv.detection.config` (sections ``detection`` and ``redetect`` of
``config.json``). Each word below means one thing in the code, the settings and the docs.

pass
    One network run over an image region scaled into a network input
    (:class:`~pedenv.detection.tiling.Pass`; kinds ``full``, ``band``, ``tile``, ``crop``, ``packed``).
whole-frame pass
    The pass over the whole frame, its input fitted to the frame's aspect (``base_long_side``).
level
    One scale of the pyramid ``far`` runs (:mod:`pedenv.detection.levels`): the whole-frame pass,
    then one level per ``level_scales`` entry, each for the people whose height in px it sees best.
band
    The image rows where a level's people can stand: from the calibration (the *ground band*,
    :mod:`pedenv.detection.geometry`, derived once per frame) or from a line fitted to the people
    the coarser levels found.
tile
    A piece of a level's band at most ``tile_width`` input px wide (neighbours overlap by
    ``TILE_OVERLAP``), so that each person is whole in one tile.
unit
    The cost measure: the network input pixels of one 384x640 input (:data:`~pedenv.detection.tiling.UNIT_PX`).
crop
    An image region around one person (a track's predicted box, a cascade candidate), scaled so
    the person has the height the network sees best (:class:`~pedenv.detection.packing.Crop`).
packed input
    Several crops placed side by side in one network input (``stream.packed_height`` x
    ``packed_width`` px), so that ten far people cost one pass (:mod:`pedenv.detection.packing`).
plan
    What one ``stream`` frame runs within its budget: how many packed inputs, which band tiles
    (:class:`~pedenv.detection.budget.FramePlan`).
budget
    The units a ``stream`` frame may spend on average (``stream.budget_units``).
credit
    Units a stream saved on quiet frames (or owes), lent to a crowded frame
    (:class:`~pedenv.detection.budget.CreditBank`, ``stream.credit_units``).
cascade candidate
    A person a pass scored below the network's threshold, small enough to be far; verified at a
    higher zoom in a packed input (:mod:`pedenv.detection.cascade`).
track search
    Looking again for the live tracks a pass missed, around where the model predicts them
    (:class:`~pedenv.records.PredictedTracks`, handed in each frame): in crops of their own for
    ``far``/``fast`` with ``redetect.enabled`` (:mod:`pedenv.detection.redetect`), in packed inputs
    for ``stream``; one matching for both (:mod:`pedenv.detection.track_search`).
merge
    The skeleton-aware NMS that makes one person of the same person seen by several passes
    (:mod:`pedenv.detection.merge`).
"""

from pedenv.detection.config import CascadeConfig, DetectionConfig, RedetectConfig, StreamConfig
from pedenv.detection.detector import Detector, backend_options, create_detector

__all__ = ["CascadeConfig", "DetectionConfig", "Detector", "RedetectConfig", "StreamConfig",
           "backend_options", "create_detector"]
