"""python -m dice_env.viewer: a page of random throws, a glTF export, usage errors, --replay."""

import json

import pytest

from dice_env.viewer import load
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
    (["--throws", "0"], "argument --throws: must be an integer >= 1, got 0"),
    (["--seed", "-1"], "argument --seed: must be an integer >= 0, got -1"),
    (["--fps", "0"], "argument --fps: must be in (0, 1000], got 0"),
    (["--out", "throw.png"], "argument --out: must end in .html, got 'throw.png'"),
    (["--glb", "throw.gltf"], "argument --glb: must end in .glb, got 'throw.gltf'"),
    (["--screenshot", "a.jpg"], "argument --screenshot: must end in .png, got 'a.jpg'"),
    (["--replay", "missing.html"], "argument --replay: no file missing.html"),
])
def test_bad_arguments_are_usage_errors(tmp_path, capsys, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2 and message in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


def test_replay_of_a_file_of_another_kind_is_a_usage_error(tmp_path, capsys):
    other = tmp_path / "throw.txt"
    other.write_text("{}")
    with pytest.raises(SystemExit) as exit_info:
        main(["--replay", str(other)])
    assert exit_info.value.code == 2
    assert "argument --replay: path must end in .html, .glb or .json, got 'throw.txt'" in \
        capsys.readouterr().err
