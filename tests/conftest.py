import os

# Must be set before Qt loads: without a display Qt would abort in the xcb plugin.
os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
