import os

# Must be set before Qt loads: without a display Qt would abort in the xcb plugin.
os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

import pytest  # noqa: E402


@pytest.fixture(autouse=True, scope="session")
def _user_folders_in_tmp(tmp_path_factory):
    """No test reads or writes the user's data folder, characters, cache or settings (and the
    start-up migration of ``app.data_dir`` never runs on the real home): all point into a
    temporary folder unless a test sets its own."""
    home = tmp_path_factory.mktemp("inkface-user")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("INKFACE_DATA", str(home / "data"))
        mp.setenv("INKFACE_ART_DIR", str(home / "data" / "characters"))
        mp.setenv("INKFACE_CACHE", str(home / "data" / "cache"))
        mp.setenv("INKFACE_SETTINGS", str(home / "settings.ini"))
        yield home


@pytest.fixture
def isolated_user_dirs(tmp_path, monkeypatch):
    """Fresh folders for this one test: settings, data, characters and cache in ``tmp_path``."""
    monkeypatch.setenv("INKFACE_SETTINGS", str(tmp_path / "settings.ini"))
    monkeypatch.setenv("INKFACE_DATA", str(tmp_path / "data"))
    monkeypatch.setenv("INKFACE_ART_DIR", str(tmp_path / "user-art"))
    monkeypatch.setenv("INKFACE_CACHE", str(tmp_path / "cache"))
    return tmp_path
