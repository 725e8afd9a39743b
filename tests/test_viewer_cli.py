"""python -m dice_env.viewer: a page of random throws, a glTF export, usage errors, --replay."""

import json
import os
import subprocess
import sys

import pytest

from dice_env.viewer import browser, load
from dice_env.viewer.__main__ import main


def test_writes_a_page_and_an_export_that_replay_as_recorded(tmp_path, capsys):
    page, glb = tmp_path / "throw.html", tmp_path / "throw.glb"
    pytest.importorskip("pygltflib")
    assert main(["--die", "d8", "--walls", "tray", "--seed", "3", "--throws", "2",
                 "--fps", "30", "--out", str(page), "--glb", str(glb)]) == 0
    out = capsys.readouterr().out
    assert out.count("throw ") == 2 and f"page: {page}" in out and f"glTF: {glb}" in out
    recordings = load(page)
    assert len(recordings) == 2 and recordings[0].dice[0].name == "d8"
    assert load(glb)[0].outcome == recordings[0].outcome
    for path in (page, glb):
        assert main(["--replay", str(path)]) == 0
    assert "as recorded" in capsys.readouterr().out


def test_replay_of_a_file_that_lands_elsewhere_exits_1(tmp_path, capsys):
    page = tmp_path / "throw.html"
    main(["--seed", "1", "--out", str(page)])
    data = [rec.to_data() for rec in load(page)]
    data[0]["outcome"]["faces"] = [7 - data[0]["outcome"]["faces"][0]]
    edited = tmp_path / "edited.json"
    edited.write_text(json.dumps(data))
    capsys.readouterr()
    assert main(["--replay", str(edited)]) == 1
    assert "the replay landed other faces: throw 0" in capsys.readouterr().err


@pytest.mark.parametrize(("argv", "message"), [
    (["--num-dice", "0"], "argument --num-dice: must be in [1, "),
    (["--throws", "0"], "argument --throws: must be in [1, "),
    (["--throws", "1000000"], "] (their frames fit the memory for records), got 1000000"),
    (["--num-dice", "12", "--throws", "20000"], "argument --throws: must be in [1, "),
    (["--seed", "-1"], "argument --seed: must be an integer >= 0, got -1"),
    (["--fps", "0"], "argument --fps: must be in [1, 1000] frames per simulated second, got 0"),
    (["--fps", "0.19"], "argument --fps: must be in [1, 1000] frames per simulated second"),
    (["--fps", "5e-324"], "argument --fps: must be in [1, 1000] frames per simulated second"),
    (["--at", "0.2"], "argument --at: must be in [0, 5] s (t_max) with --screenshot, got 0.2 "
                      "without it"),
    (["--at", "nan", "--screenshot", "a.png"], "argument --at: must be in [0, 5] s (t_max) with "
                                               "--screenshot, got nan"),
    (["--at", "-1", "--screenshot", "a.png"], "argument --at: must be in [0, 5] s"),
    (["--at", "99", "--screenshot", "a.png"], "argument --at: must be in [0, 5] s"),
    (["--out", "missing/throw.html"], "argument --out: no folder 'missing' to write 'throw.html'"),
    (["--glb", "missing/a.glb"], "argument --glb: no folder 'missing' to write 'a.glb' in"),
    (["--out", "throw.png"], "argument --out: must end in .html, got 'throw.png'"),
    (["--glb", "throw.gltf"], "argument --glb: must end in .glb, got 'throw.gltf'"),
    (["--screenshot", "a.jpg"], "argument --screenshot: must end in .png, got 'a.jpg'"),
    (["--replay", "missing.html"], "argument --replay: no file missing.html"),
])
def test_bad_arguments_are_usage_errors(tmp_path, capsys, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr("dice_env.viewer.__main__.random_throws", _no_work)
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2 and message in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


def _no_work(*args, **keywords):
    raise AssertionError("throws simulated before every argument was checked")


def test_a_screenshot_without_chromium_is_refused_before_any_work(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(browser, "chromium", lambda: None)
    monkeypatch.setattr("dice_env.viewer.__main__.random_throws", _no_work)
    with pytest.raises(SystemExit) as exit_info:
        main(["--out", str(tmp_path / "a.html"), "--screenshot", str(tmp_path / "a.png")])
    assert exit_info.value.code == 2
    assert "argument --screenshot: no Chromium found" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


def test_an_export_without_pygltflib_is_refused_before_any_work(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("importlib.util.find_spec", lambda name, *args: None)
    monkeypatch.setattr("dice_env.viewer.__main__.random_throws", _no_work)
    with pytest.raises(SystemExit) as exit_info:
        main(["--out", str(tmp_path / "a.html"), "--glb", str(tmp_path / "a.glb")])
    assert exit_info.value.code == 2
    assert "argument --glb: needs pygltflib (pip install 'dice_env[gltf]')" in \
        capsys.readouterr().err
    assert not list(tmp_path.iterdir())


def test_replaying_a_glb_without_pygltflib_is_a_usage_error(tmp_path, capsys, monkeypatch):
    glb = tmp_path / "a.glb"
    glb.write_bytes(b"glTF")
    monkeypatch.setattr("importlib.util.find_spec", lambda name, *args: None)
    with pytest.raises(SystemExit) as exit_info:
        main(["--replay", str(glb)])
    assert exit_info.value.code == 2
    assert "reading a .glb needs pygltflib (pip install 'dice_env[gltf]')" in \
        capsys.readouterr().err


def test_a_file_that_exists_is_overwritten_only_with_force(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["--seed", "1"]) == 0  # the default --out, throw.html
    page = tmp_path / "throw.html"
    before = page.read_bytes()
    (tmp_path / "a.glb").write_bytes(b"")
    with monkeypatch.context() as patch:
        patch.setattr("dice_env.viewer.__main__.random_throws", _no_work)
        for argv in ([], ["--seed", "2"], ["--out", str(page)],
                     ["--out", "b.html", "--glb", "a.glb"]):
            with pytest.raises(SystemExit) as exit_info:
                main(argv)
            assert exit_info.value.code == 2 and "exists: pass --force" in capsys.readouterr().err
    assert page.read_bytes() == before and (tmp_path / "a.glb").read_bytes() == b""
    assert main(["--seed", "2", "--force"]) == 0
    assert page.read_bytes() != before


def test_replay_of_a_file_of_another_kind_is_a_usage_error(tmp_path, capsys):
    other = tmp_path / "throw.txt"
    other.write_text("{}")
    with pytest.raises(SystemExit) as exit_info:
        main(["--replay", str(other)])
    assert exit_info.value.code == 2
    assert "argument --replay: path must end in .html, .glb or .json, got 'throw.txt'" in \
        capsys.readouterr().err


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """A page of one throw and the data of its recordings."""
    page = tmp_path_factory.mktemp("recorded") / "throw.html"
    assert main(["--seed", "4", "--fps", "30", "--out", str(page)]) == 0
    return page, [rec.to_data() for rec in load(page)]


def _written(tmp_path, name, data):
    path = tmp_path / name
    path.write_text(data if isinstance(data, str) else json.dumps(data))
    return path


def _edited(data, **changes):
    return [{**data[0], **changes}]


@pytest.mark.parametrize(("name", "content", "message"), [
    ("empty.json", "[]", "holds no recordings"),
    ("object.json", "{}", "holds no recordings"),
    ("page.html", "<html></html>", "is not a page of dice_env.viewer.write_html"),
    ("deep.json", "[" * 100_000 + "]" * 100_000, "JSON nested too deeply"),
    ("cut.json", '[{"format": "dice_env.throw", "t": [0', "not whole JSON (truncated or edited?)"),
    ("empty.glb", "", "is not a binary glTF"),
    ("header.glb", "glTF\x02\x00\x00\x00\x0c\x00\x00\x00", "is not a binary glTF"),
    ("list.json", "[[]]", "recording 0: data must be a recording"),
])
def test_replay_of_a_file_it_cannot_use_exits_2_with_the_reason(tmp_path, capsys, name, content,
                                                                 message):
    path = _written(tmp_path, name, content.encode().decode("unicode_escape"))
    with pytest.raises(SystemExit) as exit_info:
        main(["--replay", str(path)])
    error = capsys.readouterr().err
    assert exit_info.value.code == 2 and message in error and "Traceback" not in error


@pytest.mark.parametrize("edit", ["missing", "dice", "below", "until", "fps", "frames", "nested"])
def test_replay_of_a_recording_it_cannot_use_exits_2_with_the_reason(tmp_path, capsys, recorded,
                                                                     edit):
    _, data = recorded
    item = json.loads(json.dumps(data[0]))
    if edit == "missing":
        del item["contact"]
    elif edit == "dice":
        item["dice"] = item["dice"] * 2
    elif edit == "below":
        item["release"]["position"][0][2] = -0.05
    elif edit == "until":
        item["run"]["until"] = "never"
    elif edit == "fps":
        item["fps"] = 5e-324
    elif edit == "nested":
        for _ in range(900):
            item["dice"] = [item["dice"]]
    else:
        item["t"] = item["t"][::-1]
    path = _written(tmp_path, "edited.json", [item])
    with pytest.raises(SystemExit) as exit_info:
        main(["--replay", str(path)])
    error = capsys.readouterr().err.splitlines()
    assert exit_info.value.code == 2 and error[-1].startswith(
        "python -m dice_env.viewer: error: argument --replay: ")
    assert edit != "nested" or error[-1].endswith("recording 0: data nested too deeply to be a "
                                                  "recording")


def test_replay_exit_status_in_a_shell(tmp_path, recorded):
    """0: the faces as recorded; 1: one differs; 2: a file it cannot use, in one line."""
    page, data = recorded
    faces = [7 - data[0]["outcome"]["faces"][0]]
    other = _edited(data, outcome={**data[0]["outcome"], "faces": faces})
    truncated = tmp_path / "cut.glb"
    pytest.importorskip("pygltflib")
    assert main(["--replay", str(page)]) == 0
    from dice_env.viewer import write_glb

    whole = write_glb(load(page)[0], tmp_path / "whole.glb").read_bytes()
    truncated.write_bytes(whole[:len(whole) // 2])
    for path, status in ((page, 0), (_written(tmp_path, "other.json", other), 1),
                         (truncated, 2), (_written(tmp_path, "empty.json", "[]"), 2)):
        run = subprocess.run([sys.executable, "-m", "dice_env.viewer", "--replay", str(path)],
                             capture_output=True, text=True, timeout=120, env=os.environ)
        assert run.returncode == status, run.stderr
        assert "Traceback" not in run.stderr
        if status == 2:
            assert run.stderr.splitlines()[-1].startswith(
                "python -m dice_env.viewer: error: argument --replay: ")
