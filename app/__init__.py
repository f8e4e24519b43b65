"""Everything with a window, and the program's command line. The only package that imports Qt;
windows are thin and call the core (:mod:`tracker`, :mod:`training`, :mod:`morph`, :mod:`art_sets`).

Where to find what:

* ``main_window``       — the performance window (video with the tracker's overlay, the character)
* ``views``             — its picture widgets; ``settings`` — what the window remembers
* ``calibration_window`` — freeze a frame and click (or Auto and adjust) the five points
* ``training_window``   — pairing drawings with frames, and the expression space
* ``rerender_dialog``   — a recorded track again with another character
* ``editor/``           — the art-set editor (its document, canvases, panels, preview)
* ``workers``           — capture, tracking and rendering in a separate engine process;
  ``channel`` — the window ↔ engine channel on which neither side waits for the other
* ``record``            — MP4, GIF or PNG-sequence recording of the character
* ``net``               — the teleconference split over UDP (no Qt)
* ``cli``, ``__main__`` and the ``*_cmd`` modules — ``python -m app [window|demo|render|edit|
  sheet|send|receive]``
* ``data_dir``          — the one folder where Inkface keeps what the user makes
* ``qt_env``            — platform plugin choice before Qt starts (offscreen without a display)
"""
