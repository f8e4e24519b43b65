"""Tracking: a face in a video frame in, ten numbers (:class:`~tracker.params.FaceParams`) out.

Where to find what:

* ``face_tracker``  — the frame loop (:class:`FaceTracker`): head motion → eyes → mouth → checks
  against the calibrated face → ``FaceParams`` with an honest status, and the face found again
  after it is lost
* ``calibration``   — one frame and the five clicks → everything learned about one performer
  (:class:`FaceFrame`, the upright face crop every finder works in, lives here too)
* ``clicks``        — the five clicks (CLICKS.json); ``auto_init`` finds them by machine (``--auto``)
* ``head_motion``   — the head as a rigid thing: sparse optical flow on the face, frame to frame
* ``face_finder``   — the face detector and the small face picture that pins the head's position
* ``eyes``          — the eye finder for real faces: iris (disc darkness, ring votes, the iris
  picture's correlation), lids, brows, the limbus snap of clicked pupils
* ``mouth_model``   — what calibration learns about the lips, the gap and the mouth's inside
* ``mouth_finder``  — the mouth finder for real faces: the line between the lips, the lips'
  thickness on vertical profiles, the corners
* ``colour_model``  — the per-performer colour classifiers (lookup tables over a colour grid)
* ``pupils``, ``lids``, ``brows``, ``mouth`` — the paper's finders (colour tags, eye-picture
  correlation, lid walk, 1-D brow template, lip blob → radial polygon → snake); ``legacy``
  runs them for calibrations saved before the real-face models existed, and ``brows`` also
  holds the column profiles the real-face brow search reads
* ``params``        — ``FaceParams``, its CSV and the 8-bit packet; ``stream_codec`` compresses
  the packet stream; ``fap`` exports and imports MPEG-4 face animation parameters
* ``sources``       — frame sources: video file, camera, the synthetic performer, a fake camera
* ``synthetic``     — the synthetic performer with exact truth (unit tests, not evidence)
* ``track_cli``, ``__main__`` — ``python -m tracker``; ``outputs``, ``atomic_file``,
  ``safe_json`` — safe writes and careful reading of user files

Nothing here imports Qt or :mod:`morph`.
"""
