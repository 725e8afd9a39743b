"""dice_env.files: a file kept for later is written whole or not at all."""

import json
import threading

import pytest

from dice_env.files import write_atomically, write_json


def test_a_write_stopped_part_way_leaves_the_old_file_and_no_other(tmp_path):
    path = write_json(tmp_path / "kept.json", {"a": 1})

    def half(f):
        f.write(b'{"a": ')
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        write_atomically(path, half)
    assert json.loads(path.read_text()) == {"a": 1}
    assert [p.name for p in tmp_path.iterdir()] == ["kept.json"]


def test_writers_of_one_file_at_once_never_share_a_temporary_name(tmp_path):
    path, inside, errors = tmp_path / "kept.json", threading.Barrier(8), []

    def write(k):
        def slow(f):
            f.write(json.dumps({"writer": k}).encode())
            inside.wait(timeout=10)  # every writer holds its temporary file open at once

        try:
            write_atomically(path, slow)
        except Exception as error:  # reported below, from the main thread
            errors.append(error)

    threads = [threading.Thread(target=write, args=(k,)) for k in range(8)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert not errors and json.loads(path.read_text())["writer"] in range(8)
    assert [p.name for p in tmp_path.iterdir()] == ["kept.json"]
