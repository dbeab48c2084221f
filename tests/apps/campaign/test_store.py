"""The result store: complete files or none, another identity is not a result, stale temp files go, one run
per directory."""

import pytest

from teleop.apps.campaign.identity import Task
from teleop.apps.campaign.store import ResultStore
from teleop.core.errors import InputError


def test_save_load_failure_and_stale_temp_files(tmp_path):
    t = Task("blind-jnd", {"seed": 1, "x": [0.1, 2]}, "x=0.1")
    with ResultStore(tmp_path) as store:
        assert store.load(t) is None and store.done_ids() == set()
        store.save_failure(t, "ValueError: boom", "Traceback ...")
        assert store.failure(t) == "ValueError: boom"
        store.save(t, {"b": 1.0000000000000002, "a": [1, 2]})
        assert store.failure(t) is None                      # a finished task forgets its failure
        assert store.load(t) == {"a": [1, 2], "b": 1.0000000000000002}
        assert store.done_ids() == {t.id}
        text = (tmp_path / "tasks" / f"{t.id}.json").read_text()
        assert text.index('"identity"') < text.index('"kind"') < text.index('"result"')  # sorted keys
        assert '"teleop_version":"' in text and text.count("\n") == 1  # one line
        other = Task("blind-jnd", {"seed": 2, "x": [0.1, 2]}, "x=0.1")
        (tmp_path / "tasks" / f"{other.id}.json").write_text(text)  # a file holding another identity
        assert store.load(other) is None
        (tmp_path / "tasks" / f"{other.id}.json").write_text('{"identity": ')  # cut short
        assert store.load(other) is None
    (tmp_path / "tasks" / f".{t.id}.json.1234abcd.json").write_text("{")  # temp file of a killed run
    with ResultStore(tmp_path) as store:
        assert not list((tmp_path / "tasks").glob(".*"))
        with pytest.raises(InputError, match="another `teleop campaign run`"):
            ResultStore(tmp_path).lock()
