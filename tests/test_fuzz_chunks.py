"""Tampered, truncated and crafted chunk files: a clean tally or the runner's own refusal."""

import io
import shutil
import time
import zipfile

import numpy as np
import pytest

from dice_env.simulation import runner as dist
from studies import many_throws as cli

CASES = 300  # tampered files, each read once (no throw is simulated): a few seconds in all
ARGV = ["--throws", "40", "--chunk", "20", "--seed", "3"]
VALUES = [np.nan, np.inf, -np.inf, -1, 0, 1, 6, 7, 2**15 - 1, 2**40, 0.5, True, False]
DTYPES = [np.bool_, np.int8, np.int16, np.int32, np.int64, np.uint64, np.float32, np.float64,
          ">i8", "U3", np.complex128]
RECORDS = ['{"spec": 1}', "[1, 2]", "7", "", "null", '{"spec": "x", "seed": 3, "index": 1}',
           "\udcff"]


def _arrays(data):
    with np.load(io.BytesIO(data)) as saved:
        return {name: saved[name] for name in saved.files}


def _npz(arrays):
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    return buffer.getvalue()


def _craft(rng, arrays):
    """``arrays`` with one outcome, or the chunk's record, changed in kind, value or shape."""
    name = str(rng.choice([*dist.OUTCOMES, "chunk"]))
    how = rng.integers(6)
    if name == "chunk" and how < 3:
        arrays[name] = np.array(RECORDS[rng.integers(len(RECORDS))])
    elif how == 0:
        arrays[name] = arrays[name].astype(DTYPES[rng.integers(len(DTYPES))])
    elif how == 1:
        values = arrays[name].astype(np.float64)
        values[rng.integers(len(values))] = VALUES[rng.integers(len(VALUES))]
        with np.errstate(invalid="ignore"):  # NaN cast to an int: any int will do
            arrays[name] = values.astype(arrays[name].dtype) if rng.random() < 0.5 else values
    elif how == 2:
        arrays[name] = np.resize(arrays[name], rng.choice([(0,), (19,), (21,), (20, 1), ()]))
    elif how == 3:
        arrays.pop(name)
    elif how == 4:
        arrays[f"extra{name}"] = arrays[name]
    else:
        arrays[name] = np.array([arrays[name], arrays[name]], dtype=object)
    return arrays


def _tamper(rng, data):
    """``data``, a chunk's bytes, truncated, overwritten in places, or rewritten crafted."""
    kind = rng.integers(4)
    if kind == 0:
        return data[:rng.integers(len(data))]
    if kind == 1:
        spoiled = bytearray(data)
        for at in rng.integers(len(data), size=rng.integers(1, 4)):
            spoiled[at] = rng.integers(256)
        return bytes(spoiled)
    if kind == 2:
        buffer = io.BytesIO()  # a zip that holds a non-array, or an .npy of another name
        with zipfile.ZipFile(buffer, "w") as archive:
            archive.writestr(str(rng.choice(["chunk.npy", "face.npy", "x.txt"])),
                             rng.bytes(rng.integers(1, 200)))
        return buffer.getvalue()
    arrays = _arrays(data)
    try:
        return _npz(_craft(rng, arrays))
    except (ValueError, TypeError):  # numpy refused to write it: write it without the change
        return data


def test_every_tampered_chunk_gives_a_tally_or_the_runners_refusal(tmp_path, capsys):
    run = tmp_path / "run"
    cli.main([*ARGV, "--out", str(run)])
    capsys.readouterr()
    chunk = run / "chunk_000001.npz"
    data, rng, outcomes = chunk.read_bytes(), np.random.default_rng(47), {"refused": 0, "read": 0}
    for case in range(CASES):
        folder = shutil.copytree(run, tmp_path / f"case{case}")
        (folder / chunk.name).write_bytes(_tamper(rng, data))
        start = time.perf_counter()
        try:
            cli.main([*ARGV, "--out", str(folder)])
        except SystemExit as exit_:
            err = capsys.readouterr().err.splitlines()
            assert exit_.code == 2, err
            assert err[-1].startswith("python -m studies.many_throws: error: "
                                      "argument --out: "), err
            assert "delete it" in err[-1] and chunk.name in err[-1], err
            outcomes["refused"] += 1
        else:  # the tampering changed nothing a run checks: a sane tally
            out = capsys.readouterr().out
            assert "nan" not in out and "Counted" in out, out
            outcomes["read"] += 1
        assert time.perf_counter() - start < 10.0, case  # read, never thrown again
        shutil.rmtree(folder)
    assert outcomes["refused"] > CASES // 2, outcomes


@pytest.mark.parametrize("record", RECORDS)
def test_a_chunk_record_of_any_kind_is_refused_by_name(tmp_path, capsys, record):
    run = tmp_path / "run"
    cli.main([*ARGV, "--out", str(run)])
    chunk = run / "chunk_000000.npz"
    chunk.write_bytes(_npz(_arrays(chunk.read_bytes()) | {"chunk": np.array(record)}))
    with pytest.raises(SystemExit) as exit_:
        cli.main([*ARGV, "--out", str(run)])
    assert exit_.value.code == 2 and chunk.name in capsys.readouterr().err.splitlines()[-1]
