"""Visual odometry: the ego vehicle's motion estimated from one camera's images.

Words used across the package, its settings and ``docs/visual_odometry.md``:

* **track**: a corner found in one frame (FAST, an absolute contrast threshold, plus faint
  Shi-Tomasi corners on the road patch) and followed into the next by pyramidal Lucas-Kanade
  optical flow, kept only when tracking it back lands where it started
  (:mod:`pedenv.odometry.features`). Corners inside the given person boxes are never used:
  people move on their own.
* **keyframe**: the frame the next ones are compared with; a frame becomes one when the image
  changed measurably since the last (:class:`~pedenv.odometry.estimator.VisualOdometry`).
* **step**: the camera's motion from a keyframe to the next: its rotation and the direction of
  its translation from the essential matrix (USAC), the translation's length in metres from
  the road (:mod:`pedenv.odometry.motion`).
* **parallax**: how far the tracks move once the rotation is taken out, pixels (median). Below
  :data:`~pedenv.odometry.motion.MIN_PARALLAX_PX` the camera did not translate measurably and
  the step's translation is zero (a static camera gives no motion, not noise).
* **road scale**: the tracks on the road patch ahead of the vehicle (placed by the calibration's
  mounting ``cam_to_vehicle``: the camera's height and pitch) move as the road plane's
  homography says; the plane's distance in step lengths (and its pitch) that fits them best,
  divided into the camera's known height over the road, is the step's length
  (:mod:`pedenv.odometry.ground`).
* **road alignment**: for frames too far apart for the road's flow (a 2 Hz video), the road plane's
  homography that best aligns the road patch of the two images gives the step's length instead
  (:func:`~pedenv.odometry.ground.guided_road_length`).
* **matched descriptors**: when the flow loses the frames, ORB keypoints matched across them (and
  refined by the flow) give the essential matrix (:func:`~pedenv.odometry.features.match_features`).
* **lag**: ``pedenv run`` estimates the poses in its frame loop
  (:class:`~pedenv.odometry.stream.OdometryStream`): a frame's pose is final, and handed on, once
  :data:`~pedenv.odometry.stream.POSE_LAG_FRAMES` more frames were estimated; no later frame changes it.
* **static check**: a camera declared ``--static`` whose background flows between frames is refused
  (:mod:`pedenv.odometry.static_check`).
* **ego poses**: the steps chained into vehicle -> world poses, the world being the vehicle
  frame of the first frame (x forward, y left, z up, origin on the road under the vehicle):
  :class:`~pedenv.odometry.estimator.VisualOdometry`, written as ``ego_poses_estimated.csv`` in
  the ``--ego-poses`` format (:mod:`pedenv.odometry.poses_file`).

The one error: a frame with too few trackable corners or too few tracks that agree on one
motion, with no matched descriptors to take over (too dark, blurred, or covered), stops the
estimate with an InputError naming it.
"""
