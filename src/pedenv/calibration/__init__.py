"""A static camera estimated from the people it sees (self-calibration).

Words used across the package, its settings and ``docs/any_camera.md``:

- **observation**: one detected upright person in one image: the *foot point* (the midpoint
  of the two ankle keypoints, pixels) and the *head point* (the midpoint of the ears, on the
  body's vertical axis, else of the eyes, else the nose), with the person's track id where known.
- **span**: the world height between the ankle and the head keypoints of an upright person,
  a share of body height (:mod:`pedenv.body`) scaled by the pose source's own span
  (``span_scale``: 1 for skeletons at the anatomical table, about 0.93 for the real network).
- **camera parameters**: focal length ``f`` (pixels, square pixels, principal point at the
  image centre unless given), height ``H`` of the camera above the ground (metres), ``tilt``
  (the optical axis below the horizontal, radians) and ``roll`` (about the optical axis,
  radians). The world is the ground under the camera, x the horizontal viewing direction,
  y left, z up (the README's calibration conventions, ``mount: static``).
- **horizon**: the image line where the ground plane vanishes; the **vertical vanishing
  point** is where the people's foot-to-head lines meet.

The fit: a closed-form start from the horizon (a person's pixel span grows linearly with the
row of the feet and vanishes on the horizon) and the vertical vanishing point (which with
the horizon gives ``f`` and the tilt), then a robust least-squares fit of every person's head
point given the foot point under the height prior (1.72 m, 0.09 m: the fused method's); for a
static camera the head is placed a fitted offset ahead of the feet along the person's direction
of travel (walkers lean forward, their ankles trail the body's axis), and a walker's span is
shortened by its stride (the swing ankle off the ground, the pelvis lower).
The covariance of (f, H, tilt, roll) comes from the fit's Jacobian, counted per person, not
per image. :func:`pedenv.calibration.fit.estimate_camera` is the entry point.
"""
