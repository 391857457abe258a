"""The ``fused`` position method: ground contact, multi-frame triangulation and a height
prior, each with its own variance from the geometry, fused per frame with a chi-square
gate; the model's Kalman filter then filters the fused measurement over time.

Modules: ``cue`` (the record every cue returns), ``ground``, ``triangulation``,
``height`` (the three cues), ``fusion`` (gate and information-weighted mean),
``history`` (each track's past rays), ``locator`` (the ``fused`` :class:`~pedenv.localization.base.Locator`).
"""
