"""The README and docs/: numbers from their JSONs, cited files present, examples that run,
docstring references that resolve, and pages that describe rather than narrate."""

import ast
import inspect
import json
import re
import sys
from dataclasses import MISSING, fields
from pathlib import Path

import pytest

from dice_env.envs.dice_throw import configure
from dice_env.envs.throw_task import ThrowTask, make_task, task_keywords
from dice_env.model.die import Die
from dice_env.model.surroundings import walls
from studies import docs_numbers, templates

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("**/*.md"))]
HISTORY = re.compile(
    r"\b(reverted|the issue|issue's|used to|formerly|previously|an earlier (run|version)|"
    r"earlier figures|now (sticks|flagged|gives|runs|takes|costs|passes|fails|rests|reads)|"
    r"no longer (flagged|sticks|fails|counted|needed)|was (changed|fixed|removed|added)|"
    r"the kernel before|commit `?[0-9a-f]{7})\b", re.I)
RUN_FILES = ("config.json", "hyperparams.json", "evaluation.json", "start.json", "summary.json")
BLOCK = """<!-- numbers env=benchmarks/results/env.json
batch {{ env.rest.batch }}, {{ env.rest.vector_env_throws_per_s | ,.0f }} throws/s
-->
TEXT<!-- /numbers -->
"""


def test_every_filled_block_and_generated_file_is_what_its_json_gives():
    assert templates.stale() == []
    assert sum(len(templates.blocks(page)) for page in PAGES) >= 2
    assert len(templates.renderers()) >= 23


def test_no_field_computes():
    """A field is one value and a format: sums, verdicts and tables are computed in Python."""
    computing = {b.where: templates.computes(b.template) for page in PAGES
                 for b in templates.blocks(page)}
    assert {where: fields for where, fields in computing.items() if fields} == {}


def test_every_generated_file_is_included_once_and_names_its_command():
    included = re.findall(r'^--8<-- "generated/([\w-]+)\.md"$',
                          "".join(p.read_text() for p in PAGES), re.M)
    files = sorted(p.stem for p in templates.GENERATED.glob("*.md"))
    # every one rendered from JSONs, so that --check covers it
    assert sorted(included) == files and set(templates.renderers()) == set(files)
    for name in files:
        head = (templates.GENERATED / f"{name}.md").read_text().partition("\n")[0]
        assert re.fullmatch(r"<!-- --8<-- \[start:generated\] written by python -m studies"
                            r"[\w. -]*( from [\w./, -]+\.json)?: do not edit \(.*\) -->",
                            head), name
        assert templates.renderers()[name].command in head, name


def test_a_number_changed_by_hand_or_a_missing_json_is_found(tmp_path, monkeypatch):
    page = tmp_path / "page.md"
    page.write_text(BLOCK.replace("TEXT", ""))
    assert templates.fill(page)
    (block,) = templates.blocks(page)
    assert block.text.startswith("batch 256, ") and block.render() == block.text
    page.write_text(page.read_text().replace("batch 256", "batch 512"))
    (block,) = templates.blocks(page)
    assert block.render() != block.text
    monkeypatch.setattr(templates, "pages", lambda: [page])
    monkeypatch.setattr(docs_numbers, "GENERATED", {})
    monkeypatch.setattr(docs_numbers, "STUDY_MODULES", ())
    assert templates.main(["--check"]) == 1
    page.write_text(BLOCK.replace("env.json", "gone.json"))
    with pytest.raises(FileNotFoundError, match=r"gone\.json is not in the repository"):
        templates.blocks(page)[0].render()


def test_a_generated_file_changed_by_hand_is_found_and_rewritten(tmp_path, monkeypatch):
    monkeypatch.setattr(templates, "GENERATED", tmp_path)
    monkeypatch.setattr(templates, "pages", lambda: [])
    speed = {"env-speed": docs_numbers.GENERATED["env-speed"]}
    monkeypatch.setattr(docs_numbers, "GENERATED", speed)
    monkeypatch.setattr(docs_numbers, "STUDY_MODULES", ())
    assert templates.stale() == [str(tmp_path / "env-speed.md")]  # missing
    assert templates.write_generated() == [tmp_path / "env-speed.md"]
    assert templates.stale() == [] and templates.write_generated() == []
    path = tmp_path / "env-speed.md"
    text = path.read_text()
    assert text.startswith("<!-- --8<-- [start:generated] written by python -m studies.templates "
                           "from benchmarks/results/env.json") and not text.endswith("\n")
    path.write_text(text.replace("batch 256", "batch 512"))
    assert templates.main(["--check"]) == 1
    assert templates.main([]) == 0 and path.read_text() == text


def test_a_field_is_one_value_and_a_format():
    names = {"env": templates.wrap({"rest": {"batch": 256, "rates": [0.5, 0.25]}})}
    assert templates.field(names, " env.rest.batch | ,d ", "here") == "256"
    assert templates.field(names, " env.rest.rates.1 | .2f ", "here") == "0.25"
    assert templates.computes("{{ env.rest.batch }} {{ sum(env.rest.rates) | .2f }}") == [
        "{{ sum(env.rest.rates) | .2f }}"]
    with pytest.raises(KeyError, match=r"here: \{\{ env\.rest\.gone \}\}: no such value"):
        templates.field(names, " env.rest.gone ", "here")
    with pytest.raises(ValueError, match=r"one value and a format"):
        templates.field(names, " sum(env.rest.rates) | .2f ", "here")


def test_the_environment_page_lists_every_keyword():
    page = (ROOT / "docs/environment.md").read_text()
    table = page[page.index("## Keywords"):page.index("### Keywords and a base scene")]
    env = {name for name, p in inspect.signature(configure).parameters.items()
           if p.kind is p.KEYWORD_ONLY or name == "render_mode"}
    missing = [name for name in sorted(task_keywords() | env) if f"`{name}`" not in table]
    assert missing == []


def test_the_keyword_table_gives_the_code_defaults():
    """Each default the table states as a value is the one the code uses (``Scene()`` and
    formulas such as ``n`` are left to the text)."""
    page = (ROOT / "docs/environment.md").read_text()
    table = page[page.index("## Keywords"):page.index("### Keywords and a base scene")]
    task, built = make_task(), {}
    built.update({f.name: f.default for f in fields(ThrowTask) if f.default is not MISSING})
    built.update({n: p.default for n, p in inspect.signature(configure).parameters.items()
                  if p.default is not p.empty})
    built.update(release_height=task.release_height, t_max=task.scene.t_max,
                 num_dice=task.n_dice, die=task.scene.die, walls=task.scene.walls, scene=None,
                 tilt_deg=0 if task.scene.ground.normal == (0.0, 0.0, 1.0) else None)
    same = {"die": lambda name: Die.standard(name), "walls": walls}
    checked = 0
    for row in re.findall(r"^\| (`.*?) \| (.*?) \|", table, re.M):
        names = re.findall(r"`(\w+)`", row[0].split("(")[0])
        try:
            values = ast.literal_eval(f"({row[1]},)")
        except (ValueError, SyntaxError):
            continue  # `Scene()` or a formula
        for name, value in zip(names, values, strict=True):
            assert built[name] == same.get(name, lambda v: v)(value), (name, value)
            checked += 1
    assert checked >= 20


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_cited_json_is_in_the_repository(page):
    # a generated file reads as part of the page that includes it, in docs/
    folder = ROOT / "docs" if page.parent == templates.GENERATED else page.parent
    for cited in set(re.findall(r"[\w./-]+\.json\b", page.read_text())):
        if cited.startswith(("runs/", "eval/")) or cited in RUN_FILES:
            continue  # a run folder's own files, written by train.py
        assert (ROOT / cited).is_file() or (folder / cited).is_file(), \
            f"{page.relative_to(ROOT)} cites {cited}, which is not in the repository"


@pytest.mark.parametrize("path", sorted((ROOT / "benchmarks/results").glob("*.json")),
                         ids=lambda p: p.name)
def test_every_result_json_records_its_command_and_commit(path):
    report = json.loads(path.read_text())
    assert report.get("command", "").startswith("python "), path.name
    assert not re.search(r"(^|\s)(/|~)", report["command"]), f"{path.name}: a local path"
    assert report.get("commit") not in (None, "", "unknown"), path.name


def test_a_benchmark_command_writes_a_local_tree_as_its_placeholder(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT / "benchmarks"))
    import harness

    monkeypatch.setattr(sys, "argv", ["benchmarks/kernel_ab.py", f"{tmp_path}/", "--rounds", "9"])
    assert harness.command_line({tmp_path: "BASE"}) == \
        "python benchmarks/kernel_ab.py BASE --rounds 9"


def test_every_docstring_reference_names_something():
    sys.path.insert(0, str(ROOT / "docs" / "hooks"))
    try:
        import references
    finally:
        sys.path.pop(0)
    assert references.unresolved(ROOT) == []


@pytest.mark.parametrize("path", [*PAGES, *sorted((ROOT / "dice_env").glob("**/*.py")),
                                  *sorted((ROOT / "agents").glob("**/*.py"))],
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_pages_and_code_describe_rather_than_narrate(path):
    if path.name == "changelog.md":
        return
    found = [m.group(0) for m in HISTORY.finditer(path.read_text())]
    assert found == [], f"{path.relative_to(ROOT)}: history belongs in git and CHANGELOG.md"


def test_the_readme_fits_a_front_door():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 150
    head = text[:text.index("## Three starts")]
    assert "bash .ci/setup && .venv/bin/python train.py" in head
    assert "bash .ci/setup && .venv/bin/python -m pytest" in head


EXAMPLE = re.compile(r"(?:<!-- example not run: (?P<why>[^>]*?) -->\n)?```python\n(?P<code>.*?)```",
                     re.S)
# Budgets cut in the default suite (the slow test runs the pages as written).
SHORTER = {'model.learn(hp["n_timesteps"])': "model.learn(1)"}  # PPO for one rollout
EXAMPLE_PAGES = [page for page in PAGES if "```python" in page.read_text()]


def run_examples(page: Path, shorter: dict[str, str]) -> dict:
    """Run ``page``'s python blocks in order in one namespace (the last block's names)."""
    text, scope = page.read_text(), {}
    for match in EXAMPLE.finditer(text):
        if match["why"] is None:
            code = match["code"]
            for long, short in shorter.items():
                code = code.replace(long, short)
            line = text.count("\n", 0, match.start("code"))
            exec(compile("\n" * line + code, str(page.relative_to(ROOT)), "exec"), scope)
    return scope


@pytest.mark.parametrize("page", [p for p in EXAMPLE_PAGES if p.name != "README.md"],
                         ids=lambda p: p.name)
def test_every_example_runs(page, tmp_path, monkeypatch):
    """Each page's examples as written, budgets cut (``SHORTER``), in a temporary folder (the
    README's: the next test)."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr("builtins.print", lambda *a, **k: None)
    run_examples(page, SHORTER)


@pytest.mark.budget
@pytest.mark.parametrize("page", [p for p in EXAMPLE_PAGES
                                  if any(long in p.read_text() for long in SHORTER)],
                         ids=lambda p: p.name)
def test_every_example_runs_at_its_budget(page, tmp_path, monkeypatch):
    """The training examples at their full budgets (PPO's 800,000 throws): ``-m budget``."""
    monkeypatch.chdir(tmp_path)
    run_examples(page, {})


def test_an_example_left_out_says_why():
    for page in EXAMPLE_PAGES:
        text = page.read_text()
        whys = [m["why"] for m in EXAMPLE.finditer(text) if m["why"] is not None]
        assert len(whys) == text.count("<!-- example not run"), page.name  # each before a block
        assert all(why.strip() for why in whys), page.name
    assert {"README.md", "guide.md", "environment.md", "viewer.md"} <= {
        p.name for p in EXAMPLE_PAGES}


def test_the_readme_starts_run(tmp_path, monkeypatch):
    """The README's three examples, as written (PPO for one rollout instead of its budget)."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr("builtins.print", lambda *a, **k: None)
    scope = run_examples(ROOT / "README.md", SHORTER)
    assert len(EXAMPLE.findall((ROOT / "README.md").read_text())) == 3
    assert scope["result"].face.shape == (100,) and scope["both"].face.shape == (100, 2)
    assert scope["model"].num_timesteps > 0 and scope["model"].env is scope["env"]

def refused_examples() -> list[tuple[str, str]]:
    """docs/environment.md's refusals: (keywords, the message fragment the page gives)."""
    page = (ROOT / "docs/environment.md").read_text()
    table = page[page.index("| limit | why | refused, e.g. |"):]
    table = table[:table.index("\n\n")]
    rows = re.findall(r"^\|[^|]*\|[^|]*\| (.*?) \| `(.*?)` \|$", table, re.M)
    return [(example, message) for examples, message in rows
            for example in re.findall(r"`(.*?)`", examples)]


@pytest.mark.parametrize(("keywords", "message"), refused_examples())
def test_each_documented_refusal_gives_its_documented_message(keywords, message):
    import gymnasium as gym

    kwargs = eval(f"dict({keywords})")  # the page's own keyword set
    make = gym.make_vec if "num_envs" in kwargs else gym.make
    with pytest.raises(ValueError) as refused:
        make("DiceThrow-v0", **kwargs)
    assert message in str(refused.value)


def test_every_refusal_row_is_checked():
    assert len(refused_examples()) >= 20


@pytest.mark.parametrize("module", docs_numbers.STUDY_MODULES)
def test_a_study_s_generated_file_edited_by_hand_fails_the_check(module, tmp_path, monkeypatch):
    files = {name: g for name, g in templates.renderers().items()
             if g.render.__module__ == module}
    assert files, module
    for name in files:
        (tmp_path / f"{name}.md").write_text((templates.GENERATED / f"{name}.md").read_text())
    monkeypatch.setattr(templates, "GENERATED", tmp_path)
    monkeypatch.setattr(templates, "pages", lambda: [])
    monkeypatch.setattr(docs_numbers, "GENERATED", files)
    monkeypatch.setattr(docs_numbers, "STUDY_MODULES", ())
    assert templates.stale() == []
    for name in files:  # one number changed by hand in each file
        path = tmp_path / f"{name}.md"
        head, _, body = path.read_text().partition("\n")
        digit = re.search(r"\d", body)
        if digit is None:
            continue
        path.write_text(f"{head}\n{body[:digit.start()]}{(int(digit[0]) + 1) % 10}"
                        f"{body[digit.end():]}")
        assert templates.stale() == [str(path)], name
        assert templates.main(["--check"]) == 1
        assert templates.main([]) == 0 and templates.stale() == []
