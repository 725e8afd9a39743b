"""Many throws in seeded chunks: exact merges, resumable run folders, the same tally on Ray."""

import functools
import json
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass

import numpy as np
import pytest

from dice_env import throws as hands
from dice_env.disk import write_atomically
from dice_env.model.die import Die
from dice_env.model.scene import Scene
from dice_env.simulation import runner as dist
from dice_env.simulation.chunks import FolderError, prepare
from studies import many_throws as cli
from studies import run as run_study
from studies import shapes as sh
from studies.__main__ import main as studies_main
from studies.common import kept_chunks
from studies.many_throws import hand_faces

THROWS, CHUNK, SEED = 120, 30, 7  # four chunks of default-d6 throws: about 0.3 s in all


def throws(**kwargs):
    options = {"chunk": CHUNK, "seed": SEED} | kwargs
    return dist.run_throws(Scene(), THROWS, **options)


@pytest.fixture(scope="module")
def reference():
    """The tally of the run in this process, without a folder."""
    return throws()


def outcomes_of(spec):
    return [dist.throw_chunk(spec, i) for i in range(spec.n_chunks)]


def test_chunk_generators_are_the_spawned_children_of_the_seed():
    spec = dist.Spec(Scene(), THROWS, CHUNK, SEED)
    children = np.random.SeedSequence(SEED).spawn(spec.n_chunks)
    for i, child in enumerate(children):
        assert np.array_equal(spec.rng(i).integers(0, 2**62, 4),
                              np.random.default_rng(child).integers(0, 2**62, 4))
    assert [spec.size(i) for i in range(spec.n_chunks)] == [30, 30, 30, 30]
    assert dist.Spec(Scene(), 100, 30, 0).size(3) == 10


def test_tallies_merge_exactly_in_any_order():
    spec = dist.Spec(Scene(), 60, 20, SEED)
    parts = outcomes_of(spec)
    tallies = [dist.Tally.of(spec.scene, o) for o in parts]
    merged = dist.Tally.merge(tallies)
    assert merged.same_as(dist.Tally.merge(tallies[::-1]))
    every = {name: np.concatenate([o[name] for o in parts]) for name in dist.OUTCOMES}
    assert merged.throws == 60 == merged.time_hist.sum() == merged.impacts_hist.sum()
    assert np.array_equal(merged.counts, np.bincount(every["face"][every["counted"]],
                                                     minlength=7)[1:])
    for name in dist.MOMENTS:
        values = every[name].astype(float)
        assert merged.mean(name) == pytest.approx(values.mean(), rel=1e-13)
        assert merged.std(name) == pytest.approx(values.std(ddof=1), rel=1e-9)
    assert merged.faces.ended + merged.faces.undecided == 60
    with pytest.raises(ValueError, match="name must be one of"):
        merged.mean("energy")


def test_an_interrupted_run_resumes_from_its_saved_chunks(tmp_path, monkeypatch, reference):
    computed, real = [], dist.throw_chunk

    def interrupted_after_two(spec, index, num_threads=None):
        if len(computed) == 2:
            raise KeyboardInterrupt
        computed.append(index)
        return real(spec, index, num_threads)

    monkeypatch.setattr(dist, "throw_chunk", interrupted_after_two)
    with pytest.raises(KeyboardInterrupt):
        throws(out=tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "chunk_000000.npz", "chunk_000001.npz", "spec.json"]
    computed.clear()
    resumed = throws(out=tmp_path)
    assert computed == [2, 3]  # the saved chunks are read, not thrown again
    assert resumed.same_as(reference)
    computed.clear()
    assert throws(out=tmp_path).same_as(reference) and computed == []


def test_a_folder_of_another_spec_is_refused(tmp_path):
    dist.run_throws(Scene(), 30, chunk=30, seed=SEED, out=tmp_path)
    for scene, n, kwargs, what in (
            (Scene(), 60, {}, "throws 30 there, 60 asked"),
            (Scene(), 30, {"chunk": 15}, "chunk 30 there, 15 asked"),
            (Scene(), 30, {"seed": 1}, f"seed {SEED} there, 1 asked"),
            ("d20", 30, {}, "another scene"),
            (Scene(), 30, {"draw": hands.vigorous_throws}, "draw")):
        options = {"chunk": 30, "seed": SEED} | kwargs
        with pytest.raises(ValueError, match=f"holds a run of another spec.*{what}"):
            dist.run_throws(scene, n, out=tmp_path, **options)



def test_progress_is_told_the_throws_done_those_of_saved_chunks_first(folder, reference):
    told = []
    assert throws(progress=told.append).same_as(reference)
    assert told == [CHUNK] * (THROWS // CHUNK)
    (folder / "chunk_000002.npz").unlink()
    told.clear()
    assert throws(out=folder, progress=told.append).same_as(reference)
    assert told == [THROWS - CHUNK, CHUNK]  # the three chunks read back, then the one thrown


def test_progress_that_cannot_be_called_is_refused():
    with pytest.raises(TypeError, match="progress must be None or a callable taking the "
                       "throws done, got True"):
        throws(progress=True)


RUN_ALONE = ("import sys\nfrom dice_env.simulation.runner import run_throws\n"
             "run_throws('d6', 4, chunk=2)\nprint('tqdm' in sys.modules)")


def test_a_run_loads_no_progress_bar():
    env = os.environ | {"DICE_ENV_QUIET_COMPILE": "1"}
    done = subprocess.run([sys.executable, "-c", RUN_ALONE], capture_output=True, text=True,
                          env=env, timeout=300, check=True)
    assert done.stdout.split() == ["False"]

@pytest.mark.parametrize(("kwargs", "match"), [
    ({"throws": 0}, "throws must be an int >= 1"), ({"chunk": 0}, "chunk must be an int >= 1"),
    ({"seed": -1}, "seed must be an int >= 0"), ({"throws": 2.5}, "throws must be an int"),
    ({"scene": "d7"}, "scene must be a Scene or one of"), ({"ray": ""}, "ray must be None"),
    ({"workers": 0}, "workers must be None or an int >= 1"),
    ({"max_retries": -1}, "max_retries must be an int >= 0")])
def test_bad_arguments_are_refused(kwargs, match):
    options = {"scene": Scene(), "throws": 10} | kwargs
    with pytest.raises(ValueError, match=match):
        dist.run_throws(options.pop("scene"), options.pop("throws"), **options)


def test_without_ray_the_error_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray raises ImportError
    with pytest.raises(ImportError, match=r"pip install 'dice_env\[ray\]'"):
        throws(ray="local")


def test_command_line_prints_the_chi_square_summary(capsys):
    cli.main(["--die", "d6", "--throws", "60", "--chunk", "30", "--seed", "1"])
    text = capsys.readouterr().out
    assert "## d6: 60 throws in chunks of 30, seed 1, in this process" in text
    assert "Chi-square of uniformity: chi2 =" in text and "(5 degrees of freedom)" in text


def test_the_shapes_study_throws_through_faces_of(tmp_path, monkeypatch):
    calls = []

    def faces_of(scene, n, seed):
        calls.append(seed)
        return hands.Faces.of(np.full(scene.die.n_faces, n // scene.die.n_faces), n)

    monkeypatch.setattr(sh, "free_flight", lambda *a, **k: dict.fromkeys(sh.FLIGHT_COLUMNS, 0.0))
    monkeypatch.setitem(sh.FIGURES, "shapes_faces", lambda *a: None)
    run_study("shapes", tmp_path, quick=True, faces_of=faces_of)
    assert len(calls) == 2 * len(sh.DICE) == len(set(calls))  # one seed per die, fair and loaded
    page = (tmp_path / "shapes.md").read_text()
    assert "shapes --quick --chunks DIR" in page and "seeded chunks" in page
    with pytest.raises(ValueError, match="faces_of is taken by the studies shapes only"):
        run_study("fairness", tmp_path, faces_of=faces_of)
    for flag, value in (("--ray", "auto"), ("--chunks", str(tmp_path))):
        with pytest.raises(SystemExit):
            studies_main(["fairness", flag, value, "--out", str(tmp_path)])


@pytest.mark.parametrize("args", [["shapes", "--throws", "0"], ["shapes", "--ray", " "],
                                  ["shapes", "--quick", "--throws", "3"]])
def test_studies_command_line_gives_usage_errors(args, tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        studies_main([*args, "--out", str(tmp_path)])
    assert stop.value.code == 2 and "error:" in capsys.readouterr().err


def test_kept_chunks_let_a_study_continue_where_it_stopped(tmp_path):
    scene = Scene(die=Die.standard("d20"))
    first = hand_faces(scene, 40, 7, chunk=20, keep=tmp_path)
    saved = sorted(p.name for p in (tmp_path / "seed-7").iterdir())
    assert saved == ["chunk_000000.npz", "chunk_000001.npz", "spec.json"]
    (tmp_path / "seed-7" / "chunk_000001.npz").unlink()  # as if stopped after one chunk
    again = hand_faces(scene, 40, 7, chunk=20, keep=tmp_path)
    np.testing.assert_array_equal(again.counts, first.counts)
    np.testing.assert_array_equal(first.counts, hand_faces(scene, 40, 7, chunk=20).counts)


# ---- run folders trust no file they cannot check -------------------------------------------

@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    """A run folder of the four chunks of :func:`throws`."""
    folder = tmp_path_factory.mktemp("finished")
    throws(out=folder)
    return folder


@pytest.fixture
def folder(finished, tmp_path):
    """A copy of the finished run folder, to spoil."""
    return shutil.copytree(finished, tmp_path / "run")


def rewrite(path, record=None, size=None, keep_record=True):
    """The chunk at ``path`` saved again: its record updated by ``record``, cut to ``size``."""
    with np.load(path) as saved:
        arrays = {k: v[:size] for k, v in saved.items() if k != "chunk"}
        found = json.loads(str(saved["chunk"]))
    extra = {"chunk": np.array(json.dumps(found | (record or {})))} if keep_record else {}
    np.savez(path, **arrays, **extra)


def test_each_chunk_records_what_it_is(finished):
    spec = dist.Spec(Scene(), THROWS, CHUNK, SEED)
    with np.load(finished / "chunk_000002.npz") as saved:
        assert json.loads(str(saved["chunk"])) == {"spec": spec.identity, "seed": SEED,
                                                   "index": 2, "throws": CHUNK}
    assert spec.identity != dist.Spec(Scene(), THROWS, CHUNK, SEED + 1).identity


@pytest.mark.parametrize(("spoil", "match"), [
    (lambda f: rewrite(f / "chunk_000001.npz", {"seed": 8}),
     r"chunk_000001.npz' is not chunk 1 of this run \(seed 8 there, 7 here\)"),
    (lambda f: rewrite(f / "chunk_000001.npz", {"spec": "0123456789abcdef"}),
     r"chunk_000001.npz' is not chunk 1 of this run \(another spec\)"),
    (lambda f: rewrite(f / "chunk_000001.npz", {"throws": 20}, 20),
     r"chunk_000001.npz' is not chunk 1 of this run \(throws 20 there, 30 here\)"),
    (lambda f: rewrite(f / "chunk_000001.npz", size=20),  # header 30 throws, body 20
     r"chunk_000001.npz' is corrupt \(its outcomes are not .* of 30 throws each\)"),
    (lambda f: shutil.copy(f / "chunk_000001.npz", f / "chunk_000002.npz"),
     r"chunk_000002.npz' is not chunk 2 of this run \(index 1 there, 2 here\)"),
    (lambda f: shutil.copy(f / "chunk_000001.npz", f / "chunk_000004.npz"),
     r"chunk_000004.npz' is not a chunk of this run \(of chunks 0 to 3\)"),
    (lambda f: rewrite(f / "chunk_000001.npz", keep_record=False),
     r"chunk_000001.npz' records no spec, seed or index")])
def test_a_chunk_that_is_not_this_runs_is_refused_by_name(folder, spoil, match):
    spoil(folder)
    with pytest.raises(FolderError, match=match):
        throws(out=folder)


def test_deleting_the_refused_chunk_throws_it_again(folder, reference):
    rewrite(folder / "chunk_000001.npz", {"seed": 8})
    with pytest.raises(FolderError, match="delete it to throw it again"):
        throws(out=folder)
    (folder / "chunk_000001.npz").unlink()
    assert throws(out=folder).same_as(reference)


def test_chunks_without_their_spec_are_not_adopted(folder):
    (folder / "spec.json").unlink()
    with pytest.raises(FolderError, match=r"holds 4 chunks \(chunk_000000.npz, chunk_000001.npz, "
                       r"chunk_000002.npz, \.\.\.\) but no spec.json"):
        throws(out=folder, seed=SEED + 1)
    assert not (folder / "spec.json").exists()


@pytest.mark.parametrize("spoil", [
    lambda data: b"", lambda data: data[: len(data) // 2], lambda data: b"garbage" * 20,
    lambda data: data[:300] + bytes(100) + data[400:]])
def test_a_corrupt_chunk_is_refused_by_name(folder, spoil):
    path = folder / "chunk_000001.npz"
    path.write_bytes(spoil(path.read_bytes()))
    with pytest.raises(FolderError, match=r"chunk_000001.npz' is corrupt") as error:
        throws(out=folder)
    assert error.value.__cause__ is not None


def respoil(path, name, change):
    """The chunk at ``path`` saved again with its outcome ``name`` replaced by ``change(it)``."""
    with np.load(path) as saved:
        arrays = {k: saved[k] for k in saved.files}
    np.savez(path, **arrays | {name: change(arrays[name])})


def _set(value, dtype=None):
    def change(values):
        values = values.astype(dtype or values.dtype)
        values[0] = value
        return values
    return change


@pytest.mark.parametrize(("name", "change", "match"), [
    ("counted", lambda c: c.astype(np.int64), r"counted is int64, not bool"),
    ("time", _set(np.nan), r"time nan outside \[0.0, "),
    ("steps", _set(-5), r"steps -5 outside \[0, "),
    ("impacts", _set(-1), r"impacts -1 outside \[0, inf\]"),
    ("face", _set(7), r"face 7 outside \[1, 6\]"),
    ("face", _set(0), r"face 0 outside \[1, 6\]"),
    ("face", _set(2.5, np.float64), r"face is float64, not int16"),
    ("counted", lambda c: ~c, r"counted disagrees with decided, settled, unstable and sunk")])
def test_a_chunk_outcome_of_the_wrong_kind_or_range_is_refused(folder, capsys, name, change,
                                                              match):
    respoil(folder / "chunk_000001.npz", name, change)
    with pytest.raises(FolderError, match=r"chunk_000001.npz' is corrupt \(" + match):
        throws(out=folder)
    with pytest.raises(SystemExit) as exit_:  # the command line: one line, exit 2
        cli.main(["--throws", str(THROWS), "--chunk", str(CHUNK), "--seed", str(SEED),
                  "--out", str(folder)])
    last = capsys.readouterr().err.splitlines()[-1]
    assert exit_.value.code == 2 and "delete it to throw it again" in last


def test_writers_of_one_file_never_rename_each_others_temporary_files(tmp_path):
    path = tmp_path / "x.bin"

    def outer(f):
        f.write(b"outer ")
        write_atomically(path, lambda g: g.write(b"inner"))  # another writer, meanwhile
        f.write(b"done")

    write_atomically(path, outer)
    assert path.read_bytes() == b"outer done"
    assert [p.name for p in tmp_path.iterdir()] == ["x.bin"]
    with pytest.raises(ZeroDivisionError):
        write_atomically(path, lambda f: 1 / 0)
    assert [p.name for p in tmp_path.iterdir()] == ["x.bin"]


# A runner that starts when the file argv[1] appears: imported first, so both start at once.
AT_ONCE = ("import pathlib, sys, time\nfrom studies import many_throws\n"
           "print('ready', flush=True)\nwhile not pathlib.Path(sys.argv[1]).exists():\n"
           "    time.sleep(0.001)\nmany_throws.main(sys.argv[2:])")


def test_two_processes_on_one_folder_both_finish_with_the_same_tally(tmp_path):
    go, out = tmp_path / "go", tmp_path / "run"
    argv = [sys.executable, "-c", AT_ONCE, str(go), "--throws", "100", "--chunk", "2", "--seed",
            "2", "--out", str(out)]
    env = os.environ | {"DICE_ENV_QUIET_COMPILE": "1"}
    runs = [subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             env=env) for _ in range(2)]
    assert [run.stdout.readline() for run in runs] == ["ready\n"] * 2
    go.touch()  # both write spec.json, then the same chunks, at the same moments
    outs = [run.communicate(timeout=300) for run in runs]
    assert [run.returncode for run in runs] == [0, 0], [err[-600:] for _, err in outs]
    counts = [re.search(r"Counted .*", text)[0] for text, _ in outs]
    assert counts[0] == counts[1] and len(list(out.glob("chunk_*.npz"))) == 50
    assert not list(out.glob("*.partial"))


@pytest.mark.parametrize("text", [b"{not json", b"\xff\xfe\x00", b"[1, 2]"])
def test_a_corrupt_spec_is_refused_by_name(folder, text):
    (folder / "spec.json").write_bytes(text)
    with pytest.raises(FolderError, match=r"spec.json' is corrupt .*: delete out="):
        throws(out=folder)


def test_kept_chunks_refuse_corrupt_and_orphaned_files(tmp_path):
    def throw(i, size):
        return {"i": np.full(size, i)}

    prepare(tmp_path, {"chunk": 2})
    parts = kept_chunks(throw, 3, 2, tmp_path, "x")
    (tmp_path / "x-00001-1.npz").write_bytes(b"garbage")
    with pytest.raises(FolderError, match=r"x-00001-1.npz' is corrupt"):
        kept_chunks(throw, 3, 2, tmp_path, "x")
    (tmp_path / "spec.json").unlink()
    with pytest.raises(FolderError, match=r"holds 2 chunks .* but no spec.json"):
        prepare(tmp_path, {"chunk": 2})
    assert [p["i"].tolist() for p in parts] == [[0, 0], [1]]


def local_draw(scene, n, rng):
    return hands.hand_throws(scene, n, rng)


def test_draws_are_recorded_by_a_name_that_identifies_them(tmp_path, reference):
    def record(draw):
        return dist.Spec(Scene(), 10, 10, 0, draw).record()["draw"]

    assert record(hands.hand_throws) == "dice_env.throws.hand_throws"
    assert record(functools.partial(hands.hand_throws, unit=0.02)) \
        == "functools.partial(dice_env.throws.hand_throws, unit=0.02)"
    assert record(DieOnce("m")) == "DieOnce(marker='m')"

    def local(scene, n, rng):
        return hands.hand_throws(scene, n, rng)

    anonymous = lambda scene, n, rng: hands.hand_throws(scene, n, rng)  # noqa: E731
    for draw in (anonymous, local, functools.partial(local), object.__new__(Opaque)):
        with pytest.raises(ValueError, match=r"draw=.* cannot be recorded in a run folder.*"
                           "pass a module-level function or a functools.partial of one"):
            throws(out=tmp_path, draw=draw)
    assert not tmp_path.joinpath("spec.json").exists()
    assert throws(draw=anonymous).same_as(reference)  # no folder: no name needed


class Opaque:
    """A draw whose repr shows only its address."""

    def __call__(self, scene, n, rng):
        return hands.hand_throws(scene, n, rng)


@pytest.mark.parametrize(("argv", "match"), [
    (["--throws", "0"], "argument --throws: must be an int >= 1, got '0'"),
    (["--chunk", "-5"], "argument --chunk: must be an int >= 1, got '-5'"),
    (["--seed", "x"], "argument --seed: must be an int >= 0, got 'x'"),
    (["--workers", "0"], "argument --workers: must be an int >= 1, got '0'"),
    (["--ray", ""], "argument --ray: must be a Ray address"),
    (["--out", "{corrupt}"], "argument --out: .*spec.json' is corrupt"),
    (["--out", "{other}"], "argument --out: out=.* holds a run of another spec"),
    (["--out", "{file}"], "argument --out: out=.* is a file, not a folder")])
def test_command_line_gives_usage_errors_for_bad_values(tmp_path, capsys, argv, match):
    for name, text in (("corrupt", "{"), ("other", '{"throws": 1}')):
        (tmp_path / name).mkdir()
        (tmp_path / name / "spec.json").write_text(text)
    (tmp_path / "file").write_text("")
    argv = [a.format(corrupt=tmp_path / "corrupt", other=tmp_path / "other",
                     file=tmp_path / "file") for a in argv]
    with pytest.raises(SystemExit) as exit_:
        cli.main(argv)
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and err.startswith("usage: python -m studies.many_throws")
    assert any(re.search(match, line) for line in err.splitlines()), err


# ---- on a local Ray instance ---------------------------------------------------------------

@pytest.fixture(scope="module")
def ray():
    ray = pytest.importorskip("ray", reason="the Ray tests need the extra: pip install "
                              "'dice_env[ray]'")
    ray.init(address="local", num_cpus=2, include_dashboard=False)  # never a cluster found here
    # the workers unpickle this module's DieOnce by value (they cannot import a test module)
    ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])
    yield ray
    ray.shutdown()


@dataclass(frozen=True)
class DieOnce:
    """Hand throws; the first call anywhere ends its process (``marker`` records the pid)."""

    marker: str

    def __call__(self, scene, n, rng):
        try:
            fd = os.open(self.marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            return hands.hand_throws(scene, n, rng)
        os.write(fd, str(os.getpid()).encode())
        os.close(fd)
        os._exit(1)


def test_ray_gives_the_local_tally_on_one_worker_and_on_two(ray, reference):
    assert throws(ray="auto", workers=1).same_as(reference)
    assert throws(ray="auto").same_as(reference)


def test_a_worker_that_dies_loses_only_its_chunk(ray, reference, tmp_path):
    marker = tmp_path / "died"
    tally = throws(ray="auto", draw=DieOnce(str(marker)), max_retries=2)
    assert int(marker.read_text()) != os.getpid()  # a Ray worker ended itself
    assert tally.same_as(reference)


def test_a_run_interrupted_here_resumes_on_ray(ray, reference, tmp_path, monkeypatch):
    real = dist.throw_chunk

    def first_chunk_only(spec, index, num_threads=None):
        if index > 0:
            raise KeyboardInterrupt
        return real(spec, index, num_threads)

    monkeypatch.setattr(dist, "throw_chunk", first_chunk_only)
    with pytest.raises(KeyboardInterrupt):
        throws(out=tmp_path)
    monkeypatch.setattr(dist, "throw_chunk", real)
    assert throws(ray="auto", out=tmp_path).same_as(reference)
    assert hand_faces(Scene(), THROWS, SEED, ray="auto", chunk=CHUNK).counts.tolist() \
        == reference.counts.tolist()
