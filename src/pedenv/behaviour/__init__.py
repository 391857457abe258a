"""What each tracked pedestrian is about to do (beyond the paper; the ``fused`` preset).

Body orientation (:mod:`~pedenv.behaviour.orientation`, fused over time in
:mod:`~pedenv.behaviour.heading_filter`), facing the ego (:mod:`~pedenv.behaviour.facing`),
motion state (:mod:`~pedenv.behaviour.motion_state`), predicted path
(:mod:`~pedenv.behaviour.prediction`) and conflict with the ego's path
(:mod:`~pedenv.behaviour.ego_path`, :mod:`~pedenv.behaviour.conflict`), run per frame by
:class:`pedenv.behaviour.estimator.BehaviourEstimator`; thresholds in ``Config.behaviour``
(:mod:`pedenv.behaviour.config`). Nothing is imported here, so ``pedenv.config`` can import the
config module without a cycle.
"""
