"""The docs' measured numbers: each generated file's text, and the README's computed values.

Each function decorated with :func:`generated` renders ``docs/generated/NAME.md`` from the result
JSONs its keywords name (as :class:`studies.templates.Tree`: keys read as attributes); the
hand-written page includes the file (``--8<-- "generated/NAME.md"``). Every number, verdict
and sum is computed here, in Python, or in the study of :data:`STUDY_MODULES` that writes it.
:data:`VALUES` adds named values computed from a JSON to what the README's fields may read.
``python -m studies.templates`` writes them all.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from dice_env.markdown import markdown_table

PHYSICS = "benchmarks/results/physics.json"
TO_REST = "benchmarks/results/physics.json#throws_to_rest/Scene()"
STEP_LIMIT = "benchmarks/results/step_limit.json"
QUICK = "benchmarks/results/agents_quick.json"
SCRATCH = "benchmarks/results/learn_from_scratch.json"
WRITER = "python -m studies.templates"


@dataclass(frozen=True)
class Generated:
    """How ``docs/generated/NAME.md`` is made.

    Its JSONs (keyword -> ``PATH[#key/key]``), the function that renders them, and the command
    that writes the file.
    """

    sources: dict[str, str]
    render: Callable[..., str]
    command: str = WRITER


GENERATED: dict[str, Generated] = {}
# The studies whose renderers sit beside them (``python -m studies NAME`` writes their files).
STUDY_MODULES = ("studies.pips", "studies.weldon", "studies.paper_figures",
                 "studies.cuboids", "studies.shapes",
                 "studies.craps", "studies.pairs", "studies.collisions",
                 "studies.materials", "studies.validation",
                 "studies.stability", "studies.convergence",
                 "studies.fairness")


def generated(name: str, command: str = WRITER,
              **sources: str) -> Callable[[Callable[..., str]], Callable[..., str]]:
    """Register the decorated function as the renderer of ``docs/generated/NAME.md``.

    The file is written by ``command`` (a study's: ``python -m studies NAME``) from the JSONs
    ``sources`` names.
    """
    def register(render: Callable[..., str]) -> Callable[..., str]:
        GENERATED[name] = Generated(sources, render, command)
        return render
    return register


def mean(values: list[float]) -> float:
    """The mean of ``values``."""
    return sum(values) / len(values)


def yes(met: bool) -> str:
    """A goal's verdict."""
    return "yes" if met else "no"


# The README's fields: values computed from a JSON, read as if they were its keys.

def cold_start_values(cold) -> dict[str, object]:
    """``benchmarks/results/cold_start.json``: each entry point's first use, named."""
    first = dict(zip(cold.entry_points, cold.seconds.cold, strict=True))
    return {"tests_outcome": cold.suite.summary.split(" in ")[0],
            "paper_scene_cold_s": first["the paper scene (vector kernel)"],
            "group_cold_s": first["simulate_group (two d6 in the tray)"],
            "every_entry_point_cold_s": sum(cold.seconds.cold),
            "warm_under_s": math.ceil(max(cold.seconds.warm))}


def physics_values(physics) -> dict[str, object]:
    """``benchmarks/results/physics.json``: the headline speeds."""
    decided = physics.throws_to_rest["Scene()"].modes["free flight + decided face"]
    return {"paper_scene_m_die_steps_per_s":
            physics.paper_scene_die_steps_per_s.batch1024_threads2 / 1e6,
            "decided_throws_per_s_2threads": decided.batch_threads2}


def quick_values(quick) -> dict[str, object]:
    """``benchmarks/results/agents_quick.json``: each thrower's mean success over the seeds."""
    rates = quick.settings[0].rates
    return {"ppo_mean": mean(rates.PPO), "oracle_mean": mean(rates.oracle),
            "rule_mean": mean(rates["hand-written"]), "random_mean": mean(rates.random)}


def tasks_values(tasks) -> dict[str, object]:
    """``benchmarks/results/tasks.json``: each task's oracle against random, in one line."""
    return {"count": len(tasks.tasks),
            "oracle_vs_random": ", ".join(
                f"`{t.id}` {t.rates.oracle.rate:.2f} / {t.rates.random.rate:.2f}"
                for t in tasks.tasks)}


def baselines_values(b) -> dict[str, object]:
    """``benchmarks/results/baselines.json``: each task's best algorithm against the oracle."""
    return {"best_vs_oracle": ", ".join(
        f"`{r.task}` {max(v.mean for v in r.learned.values()):.2f} / {r.fixed.oracle:.2f}"
        for r in b.rows if r.learned)}


def recipe_values(learned) -> dict[str, object]:
    """``benchmarks/results/learned.json``: the recipe's PPO / oracle per task, in one line."""
    return {"recipe_summary": "; ".join(
        f"`{r.task}` {spread(r.ratio)} ({_method(r)}, {r.throws:,} throws, {len(r.seeds)} "
        f"seed{'s' if len(r.seeds) > 1 else ''}, {r.cpu_seconds / 60:.0f} min CPU)"
        for r in learned.recipe)}


VALUES: dict[str, Callable[[object], dict[str, object]]] = {
    "benchmarks/results/cold_start.json": cold_start_values,
    "benchmarks/results/physics.json": physics_values,
    QUICK: quick_values,
    "benchmarks/results/tasks.json": tasks_values,
    "benchmarks/results/baselines.json": baselines_values,
    "benchmarks/results/learned.json": recipe_values,
}


# docs/agents.md

@generated("agents-warm-start", quick=QUICK)
def agents_warm_start(quick) -> str:
    """Success of each thrower after the quick preset, over its seeds."""
    config, rates = quick.config, quick.settings[0].rates
    ppo, oracle = rates.PPO, rates.oracle
    throws = config.total_timesteps or "the preset's"
    return f"""Warm start, `{quick.command}` (preset `{config.preset}`,
{throws} throws; at {quick.commit}; the group's
`summary.json` kept as `benchmarks/results/agents_quick.json`): success over seeds
{config.seed}–{config.seed + config.seeds - 1}, mean [min, max],
{config.eval_throws} throws per thrower, the oracle on its {config.oracle_observations}
observations × 16 throws:

| thrower | success |
|---|---|
| PPO | {mean(ppo):.3f} [{min(ppo):.3f}, {max(ppo):.3f}] |
| PPO on the oracle's throws | {mean(quick.settings[0].ppo_on_oracle_throws):.3f} |
| oracle | {mean(oracle):.3f} [{min(oracle):.3f}, {max(oracle):.3f}] |
| hand-written | {mean(rates["hand-written"]):.3f} |
| random | {mean(rates.random):.3f} |
"""


def success_after(run, throws: int) -> float:
    """A learning curve's success at the first point with at least ``throws`` throws."""
    return next(p.success for p in run.curve if p.throws >= throws)


@generated("agents-from-scratch", scratch=SCRATCH)
def agents_from_scratch(scratch) -> str:
    """PPO from scratch: its curve, its end and its time."""
    run = scratch.runs[0]
    ppo = run.final.ppo
    return f"""From scratch, `{scratch.command}` (seed {run.seed}, {scratch.throws:,}
throws, {ppo.n:,} fixed evaluation throws): success
{success_after(run, 100_000):.2f} after 100k throws,
{success_after(run, 250_000):.2f} after 250k and
{ppo.success:.3f} [{ppo.ci[0]:.3f},
{ppo.ci[1]:.3f}] to rest at the end, against the hand-written rule's
{run.final.rule.success:.3f}, in {run.seconds / 60:.0f} min on
the 2 cores.
"""


# docs/environment.md

@generated("env-speed", env="benchmarks/results/env.json")
def env_speed(env) -> str:
    """The env's throws/s to rest and to a decided face."""
    rest, decided = env.rest, env.decided
    faces = "the same faces" if env.same_faces else "OTHER FACES"
    return f"""On the 2 cores (default release 1.5 cm, batch {rest.batch}, {rest.threads}
threads): to rest, kernel {rest.kernel_throws_per_s:,.0f} throws/s, vector env
{rest.vector_env_throws_per_s:,.0f} (overhead {rest.vector_overhead:.1%}),
single envs {rest.single_env_throws_per_s:,.0f}; with `until="decided"`, kernel
{decided.kernel_throws_per_s:,.0f}, vector env {decided.vector_env_throws_per_s:,.0f}
({env.decided_over_rest_vector_env:.1f}× to rest, {faces}),
single envs {decided.single_env_throws_per_s:,.0f}.
"""


@generated("env-throwers", quick=QUICK)
def env_throwers(quick) -> str:
    """Each thrower's success on ``DiceThrow-v0``, mean over the quick preset's seeds."""
    rates = quick.settings[0].rates
    return (f"random {mean(rates.random):.3f}, the hand-written rule "
            f"{mean(rates['hand-written']):.3f}, the oracle {mean(rates.oracle):.3f}, "
            f"PPO {mean(rates.PPO):.3f}.\n")


def rate(r) -> str:
    """A success rate and its interval."""
    return f"{r.rate:.2f} [{r.ci[0]:.2f}, {r.ci[1]:.2f}]"


@generated("env-tasks", tasks="benchmarks/results/tasks.json", quick=QUICK,
           b="benchmarks/results/baselines.json")
def env_tasks(tasks, quick, b) -> str:
    """The registered tasks, hardest last, and how their oracle searched."""
    budget = {r.task: r.budget for r in b.rows}
    lines = ["| id | keywords | the task | chance | random | rule | oracle | benchmark budget "
             "(throws) |", "|---|---|---|---|---|---|---|---|"]
    for t in sorted(tasks.tasks, key=lambda t: t.chance - t.rates.oracle.rate):
        keywords = ", ".join(f"`{k}={v!r}`" for k, v in t.keywords.items()) or "none"
        rules = " ".join(f"{name} {rate(r)}" for name, r in t.rates.items()
                         if name not in ("random", "oracle")) or "none"
        lines.append(f"| `{t.id}` | {keywords} | {t.description} | {t.chance:.3f} | "
                     f"{rate(t.rates.random)} | {rules} | {rate(t.rates.oracle)} | "
                     f"{budget[t.id]:,} |")
    first = tasks.tasks[0]
    two = [t for t in tasks.tasks if t.keywords.get("num_dice") == 2]
    searched = [t.oracle_throws_searched / t.oracle_observations for t in two]
    craps = next(t for t in tasks.tasks if t.id == "DiceThrowCraps-v0").on_oracle_throws
    return "\n".join(lines) + f"""

Random and the rule: {first.throws} throws each, Wilson 95 % intervals. The oracle
(`agents/oracle.py`, started from their actions) searches the first
{first.oracle_observations} of those observations of one die
({first.oracle_throws_searched / first.oracle_observations:,.0f}
simulated throws each, its default settings) and the first \
{max(t.oracle_observations for t in two)} of two dice
({min(searched):,.0f}
to {max(searched):,.0f}, a smaller search: their throws cost far more), each scored on
{first.oracle_score_samples} fresh noise draws; its interval is Wilson's over those
throws divided by the observations' design effect (`agents.evaluate.clustered`). The oracle is
a lower bound on the best success a task allows: on `DiceThrow-v0`, started also from a trained
PPO's actions, it reaches {mean(quick.settings[0].rates.oracle):.3f} (3 seeds,
[agents](agents.md)). On the craps task's oracle throws the set throw scores
{craps.set.rate:.3f}
and the oracle
{craps.oracle.rate:.3f}. Made by `{tasks.command}` in
{tasks.seconds / 60:.1f} min on {tasks.threads} cores.
"""


# docs/guide.md

@generated("guide-ray", ray="benchmarks/results/ray_overhead.json")
def guide_ray(ray) -> str:
    """Throws/s in this process and on Ray."""
    rows = ray.rows
    return f"""\
`{ray.command}` (`benchmarks/results/ray_overhead.json`, wall clock, the same tally on
every path: {all(r.same_tally for r in rows)}): {rows[0].path}
{rows[0].throws_per_s:,.0f} throws/s, {rows[1].path} {rows[1].throws_per_s:,.0f},
{rows[2].path} {rows[2].throws_per_s:,.0f}, {rows[3].path}
{rows[3].throws_per_s:,.0f}, after {ray.ray_start_s:.1f} s to start Ray; measured
at a load average of {ray.load_average:.1f} on the {ray.cpu_count} cores, so these show
how the scheduler shared the cores more than Ray's overhead.
"""


@generated("guide-training-time", scratch=SCRATCH, sb3="benchmarks/results/sb3_defaults.json")
def guide_training_time(scratch, sb3) -> str:
    """The recipe's time, and SB3's defaults against it."""
    success = sb3.success
    return f"""\
The {scratch.throws:,} throws take {scratch.runs[0].seconds / 60:.0f} min on the 2 cores, its \
evaluations included (`{scratch.command}`, [agents](agents.md)).
With SB3's defaults instead, `PPO("MlpPolicy", gym.make("DiceThrow-v0"))` runs one throw an \
episode at {sb3.throws_per_s:.0f} throws/s (one thread's CPU time) and, after {sb3.throws:,} \
throws, lands the target on {success.rate:.3f} [{success.interval[0]:.3f}, \
{success.interval[1]:.3f}] of {sb3.eval_throws} seeded throws: {success.verdict} \
(`{sb3.command}`); its learning rate and action noise are far from what the task needs.
"""


@generated("guide-weight", w="benchmarks/results/weight.json")
def guide_weight(w) -> str:
    """The library's lines per layer."""
    layers = ", ".join(f"{k} {v:,}" for k, v in w.layers.items())
    return (f"Lines of `dice_env/` per layer (`{w.command}` at {w.commit}): {layers}; "
            f"{w.total:,} in all.\n")


# docs/model.md

@generated("model-step-safety", limit=STEP_LIMIT)
def model_step_safety(limit) -> str:
    """The gentle faces' agreement at each step safety."""
    agreement = "; ".join(f"{100 * r.gentle_agreement:.1f} % at {r.safety:g}"
                          for r in limit.step_sweep)
    return f"""{agreement} in one run of
`python benchmarks/step_limit.py` on 500 throws; `docs/error-vs-runtime.md` measures the default
on its own 2,000 throws).
"""


# docs/performance.md

@generated("performance-run", physics=PHYSICS, rest=TO_REST)
def performance_run(physics, rest) -> str:
    """The run's machine, its printed tables, and MuJoCo's rest against ours."""
    machine, early = physics.machine, rest.modes["free flight + early rest"]
    decided = rest.modes["free flight + decided face"]
    return f"""\
The run: `{physics.command}` at {physics.commit} on {machine.cpu}, {machine.cores} cores
(load average {machine.load_average_start[0]:.2f} at the start), Python {machine.python},
numba {machine.numba}, numpy {machine.numpy}, MuJoCo {rest.mujoco.version} (the optional
`bench` extra). The default scene is stick-slip friction and the midpoint step at 0.15 of its
critical step ({rest.scene.dt_s:.3g} s).

```text
{physics.table}
```

Hand throws: 5–15 cm above the table, 0.5–1 m/s in a uniform direction, spin up to 30 rad/s
about a uniform axis, uniform orientation (seeded). MuJoCo: a free box of the same edge, mass
and inertia, friction 0.4, default solver and contact parameters and 2 ms step, started from
the same states, run until the same rest rule holds (lowest corner within 1 mm of the plane
standing in for "in contact"), and until the same decided-face rule holds, each timed as one
`mj_step(nstep=...)` call per throw for exactly the steps it needs. Its soft contact brings the
die to rest sooner ({rest.mujoco.mean_rest_time_s:.2f} s against \
{early.mean_rest_time_s:.2f} s) and decides sooner
({rest.mujoco.decided.mean_time_s:.2f} s against {decided.mean_rest_time_s:.2f} s), so it \
also simulates less time; stopped by the
decided-face rule it lands on its face at rest in \
{rest.mujoco.decided.same_face_as_at_rest:.3f} of throws, ours in
{decided.same_face_as_at_rest:.3f}.
"""


@generated("performance-goals", physics=PHYSICS, rest=TO_REST, limit=STEP_LIMIT)
def performance_goals(physics, rest, limit) -> str:
    """Each speed goal, what the run measured, and whether it is met."""
    paper, warm = physics.paper_scene_die_steps_per_s, physics.start.warm
    early = rest.modes["free flight + early rest"]
    decided = rest.modes["free flight + decided face"]
    budget, mujoco, loosest = rest.step_budget, rest.mujoco, limit.step_sweep[-1]
    contact = limit.contact.mujoco
    rows = [
        ("paper scene ≥ 30 M die-steps/s on 2 cores, batched",
         f"{paper.batch1024_threads2 / 1e6:.1f} M on two threads, "
         f"{paper.batch1024_threads1 / 1e6:.1f} M on one, with the vectorised kernel "
         f"(`dice_env/physics/vector_kernel.py`, below): "
         f"{paper.ratio_vectorised_vs_scalar_kernel:.2f}× the scalar kernel",
         yes(paper.batch1024_threads2 >= 30e6)),
        ("default scene ≥ 20,000 settled throws/s on 2 cores",
         f"{early.batch_threads2:,.0f} on two threads, {early.batch_threads1:,.0f} on one "
         f"(early rest); to a decided face (the face they rest on): "
         f"{decided.batch_threads2:,.0f} on two, {decided.batch_threads1:,.0f} on one",
         f"{yes(early.batch_threads2 >= 2e4)}: out of reach (below): at most "
         f"{budget.vectorised_ceiling_throws_per_s_2cores:,.0f} even at the cheapest die-step "
         f"measured; {loosest.throws_per_s_2threads:,.0f} with the explicit step at "
         f"{loosest.safety:g} of its stability limit, where the gentle faces converge in only "
         f"{100 * loosest.gentle_agreement:.0f} % of throws"),
        ("≥ 10× MuJoCo's throws to rest per second",
         f"{mujoco.ratios['free flight + early rest'].batch_1thread:.2f}× per core to rest; our "
         f"decided throws {decided.batch_threads1 / mujoco.throws_per_s_1thread:.1f}× MuJoCo's "
         f"throws to rest, {mujoco.ratios['free flight + decided face'].batch_1thread:.2f}× "
         f"MuJoCo stopped by the same energy rule",
         f"{yes(mujoco.ratios['free flight + early rest'].batch_1thread >= 10)}: against "
         f"MuJoCo's default contact, which does not bounce and sinks "
         f"{100 * contact['default contact, dt 2 ms'].landing['1.0'].sink:.0f} % of the edge on "
         f"a 1 m/s landing (at most {mujoco.vectorised_ceiling_vs_mujoco_per_core:.1f}× even at "
         f"the cheapest die-step); against MuJoCo with a contact like the table's, "
         f"{contact['stiff contact, dt timeconst/8'].ours_vs_mujoco:.1f}× (below)"),
        ("a single throw well under 1 ms",
         f"{decided.single_throw_ms:.2f} ms to a decided face; {early.single_throw_ms:.2f} ms "
         f"to rest with early rest (its floor: {budget.mean_contact_steps_before_rest:,.0f} "
         f"contact steps at the scalar step's {budget.ns_per_contact_step_1thread:.0f} ns, "
         f"{budget.floor_ms_per_throw:.2f} ms, plus the rest proof)",
         f"{yes(decided.single_throw_ms < 1)}, to a decided face"),
        ("warm start (import + first throw, cache present) under 1 s",
         f"{warm.import_and_first_throw_s:.2f} s ({warm.import_s:.2f} s import + "
         f"{warm.first_throw_s:.2f} s first throw)", yes(warm.import_and_first_throw_s < 1)),
        ("numpy listing as baseline",
         f"{paper.numpy_listing:,.0f} die-steps/s; the kernel "
         f"{paper.ratio_batch1_vs_numpy:,.0f}× (batch 1), "
         f"{paper.ratio_batch1024_2threads_vs_numpy:,.0f}× (batch 1024, 2 threads)", "—"),
    ]
    return "\n".join(["| goal | measured (the run above) | met? |", "|---|---|---|",
                      *(f"| {goal} | {measured} | {met} |" for goal, measured, met in rows)])


@generated("performance-paper-scene", paper=f"{PHYSICS}#paper_scene_die_steps_per_s")
def performance_paper_scene(paper) -> str:
    """The vectorised paper step's speed."""
    return (f"In the run above it did {paper.batch1024_threads1 / 1e6:.1f} M die-steps/s on one "
            f"thread ({1e9 / paper.batch1024_threads1:.0f} ns per die-step)\n"
            f"and {paper.batch1024_threads2 / 1e6:.1f} M on two.\n")


@generated("performance-hold", budget=f"{TO_REST}/step_budget")
def performance_hold(budget) -> str:
    """The hold's steps against the contact before it."""
    hold, contact = budget.mean_hold_steps, budget.mean_contact_steps_before_rest
    return f"""A die counts as settled after `Rest.hold` seconds (0.1 s) of quiet steps. On the default table
that hold is {hold:,.0f} steps, {hold / contact:.1f} times the contact steps of the whole throw before it
({contact:,.0f}, `step_budget` in `benchmarks/results/physics.json`), so with free flight analytic it is most of the cost.
"""  # noqa: E501


@generated("performance-batch-and-time", physics=PHYSICS)
def performance_batch_and_time(physics) -> str:
    """What the batch-size and simulated-time tables show."""
    batches, cost = physics.throws_per_s_vs_batch_2threads, physics.cost_vs_simulated_time
    growth = (cost["4.0"].ms_per_throw - cost["2.0"].ms_per_throw) / 2
    return f"""\
The batch-size table runs the same 1,024 throws as batches of each size, one after the other,
on two threads: one throw per call runs serially and pays for the Python around the kernel,
larger batches share the threads' start ({batches["1"]:,.0f} throws/s one at a time, \
{batches["1024"]:,.0f} in batches of 1,024). The
simulated-time table runs without stopping at rest: with free flight the first 0.25 s of a throw
(the fall and the first bounces) cost {cost["0.25"].ms_per_throw:.2f} ms instead of \
{cost["0.25"].ms_per_throw_plain:.2f} ms; once the die lies
on the table every step is a contact step, so both columns grow by about
{growth:.0f} ms per simulated second and meet. Stop at rest (and early rest) are what keep a \
throw cheap.
"""


@generated("performance-limit", physics=PHYSICS, rest=TO_REST, limit=STEP_LIMIT)
def performance_limit(physics, rest, limit) -> str:
    """Where a throw's steps go, and why the default-scene goals are out of reach."""
    budget, warm, sweep = rest.step_budget, physics.start.warm, limit.step_sweep
    early = rest.modes["free flight + early rest"]
    decided = rest.modes["free flight + decided face"]
    contact = budget.mean_contact_steps_before_rest
    steps = budget.mean_flight_steps + contact + budget.mean_hold_steps
    goal_ns = 1e9 / (2e4 / 2 * contact)  # per contact step, for 20,000 throws/s on 2 cores
    return f"""\
A throw on the default table (dt = {rest.scene.dt_s:.3g} s, 0.15 of the midpoint step's \
critical step) takes
about {steps:,.0f} steps to rest ({budget.throws} throws, plain stepping): \
{budget.mean_flight_steps:,.0f} in the air,
{contact:,.0f} in contact before the rest begins, and the {budget.mean_hold_steps:,.0f} of the \
hold. Free flight removes the first,
early rest most of the last, the decided face most of the contact that only settles the die;
what remains is the contact while the face is still open. To rest with early rest a throw
costs {1e3 / early.batch_threads1:.2f} ms of CPU ({early.batch_threads1:,.0f} throws/s on one \
thread), to a decided face {1e3 / decided.batch_threads1:.2f} ms
({decided.batch_threads1:,.0f}/s); a resting die's step costs \
{budget.ns_per_contact_step_1thread:.0f} ns in the scalar kernel. Everything left is
contact steps of the explicit scheme, and the two default-scene goals are out of reach for
them:

- **The number of contact steps is set by the physics and the convergence.** The die is in
  contact for about {contact:,.0f} steps before it rests (rattling, rolling and sliding over its
  ~{rest.modes["plain stepping"].mean_impacts:.0f} impacts). S = 1e5 N/m per corner (a corner \
sinks at most about 3 % of the edge) gives
  a contact period of about 0.5 ms; the midpoint step is stable only below
  {sweep[0].dt_s / sweep[0].safety:.2g} s for the stiffest mode, and the default step is 0.15 \
of that because larger
  steps cost convergence: the gentle release's faces agree with a quarter step in
  {100 * sweep[0].gentle_agreement:.1f} % of 500 throws at 0.15, \
{100 * sweep[1].gentle_agreement:.1f} % at 0.3 and {100 * sweep[-1].gentle_agreement:.1f} % at \
0.9 (table 1 below;
  `docs/error-vs-runtime.md` maps the same error against run time).
- **The cheapest die-step measured is {budget.ns_per_vectorised_paper_step_1thread:.0f} ns per \
core**: the vectorised paper step
  above. A default contact step does more arithmetic per corner in contact than the paper
  step does per corner (the midpoint velocity, the tie point's spring and its slip test on
  top of the spring, damping and friction), so a vectorised default step cannot be expected
  to be cheaper.
- **So even at the vectorised paper step's cost** a throw's contact steps take
  {budget.vectorised_floor_ms_per_throw:.2f} ms per core: at most \
**{budget.vectorised_ceiling_throws_per_s_2cores:,.0f} settled throws/s on two cores** (the \
goal of
  20,000 needs {goal_ns:.0f} ns per contact step) and at most \
**{rest.mujoco.vectorised_ceiling_vs_mujoco_per_core:.1f}× MuJoCo** per core (the goal
  is 10×), before any cost of the hold, the flight jumps, or the scalar parts. Both ceilings are
  printed by `benchmarks/physics.py` (`step_budget` and `mujoco` in the JSON) from the same
  run's measurements.
- **Longer steps do not get round it** (next section): the explicit step at \
{sweep[-1].safety:g} of its
  stability limit brings only \
{sweep[-1].throws_per_s_2threads / sweep[0].throws_per_s_2threads:.1f}× the throws/s and keeps \
the gentle faces in
  {100 * sweep[-1].gentle_agreement:.0f} % of throws; a linearly implicit contact, stable at any \
step, is no more accurate than
  the explicit one at any step; and MuJoCo's speed at its default comes from a contact that
  does not bounce.
- **What the scalar kernel leaves on the table** is at most the factor between its
  {budget.ns_per_contact_step_1thread:.0f} ns and the vector step's \
{budget.ns_per_vectorised_paper_step_1thread:.0f} ns. A branch-free default step would do the \
contact work of
  all corners, in contact or not; compacting the corners in contact into the vector pass
  would be worth at most that factor and is bounded by the same ceiling.
- **The decided face** brings the throws whose outcome is all that counts (fairness studies,
  the env's `until="decided"`) to {decided.batch_threads2:,.0f}/s on two threads, \
{decided.batch_threads2 / early.batch_threads2:.1f} times the throws to rest.
- **Warm start**: {warm.import_and_first_throw_s:.2f} s (import {warm.import_s:.2f} s, first \
throw from the cache {warm.first_throw_s:.2f} s). Loading
  the cached kernel makes numba import `scipy.linalg` to check for BLAS when scipy is
  installed, as with the test extra.
"""


@generated("performance-step-sweep", limit=STEP_LIMIT)
def performance_step_sweep(limit) -> str:
    """Table 1: the explicit step from the default up to its stability limit."""
    sweep = limit.step_sweep
    rows = "\n".join(
        f"| {r.safety:.2f}{' (default)' if i == 0 else ''} | {r.dt_s * 1e6:.1f} | "
        f"{100 * r.gentle_agreement:.1f} ± {100 * r.gentle_agreement_se:.1f} % | "
        f"{r.restitution_1mps:.3f} | {100 * r.deepest_sink_of_edge:.2f} % | "
        f"{r.throws_per_s_2threads:,.0f} | {r.mean_steps:,.0f} | "
        f"{100 * r.unstable_fraction:.1f} % |" for i, r in enumerate(sweep))
    return f"""\
**1. The explicit step, from the default up to its stability limit.** The same scheme and
scene. `safety` is the step over the critical step ({sweep[0].dt_s / sweep[0].safety:.3g} s). \
Gentle: the 5 cm release of
`docs/error-vs-runtime.md`, 500 throws, the same face at dt and dt/4 (the chaos floor, the
agreement of two runs at dt/4 of each other's perturbation, is \
{100 * min(r.chaos_floor for r in sweep):.0f} % at every step). e: a flat
landing at 1 m/s (converged {sweep[0].converged_restitution_1mps:.3f}). Throws/s: the 1,024 \
hand throws of `benchmarks/physics.py` to
early rest on two threads, in the run of `{limit.command}`.

| safety | dt (µs) | gentle faces, dt vs dt/4 | e (1 m/s) | deepest sink / edge | \
throws/s, 2 threads | steps per throw | unstable |
|---|---|---|---|---|---|---|---|
{rows}

The scheme stays stable up to the limit. What fails is accuracy: the restitution drifts and the
gentle faces stop converging as soon as the step grows. And even at {sweep[-1].safety:g}, with \
the accuracy
given up, a throw costs \
{sweep[-1].throws_per_s_2threads / sweep[0].throws_per_s_2threads:.1f}× less, not the \
{2e4 / sweep[0].throws_per_s_2threads:.0f}× that 20,000 throws/s would need: the flight
jumps, the rest test and the per-throw work do not shrink with the step.
"""


IMPLICIT_SCHEMES = ("theta 1", "theta 0.5", "theta 0.5 + onset", "explicit")


@generated("performance-implicit", implicit="benchmarks/results/implicit_contact.json")
def performance_implicit(implicit) -> str:
    """Table 2: a linearly implicit contact against the explicit step."""
    row = {(r.scheme, r.safety): r for r in implicit.rows}
    stable = {key: r.get("stable", True) for key, r in row.items()}

    def cell(r, stable: bool) -> str:
        if not stable:
            return "above its stable step"
        none = " (none settle)" if r.settled == 0 else ""
        return f"{r.restitution_1mps:.3f}, {100 * r.faces_dt_vs_dt4:.1f} %{none}"

    lines = []
    for f in sorted({r.safety for r in implicit.rows}):
        cells = " | ".join(cell(row[s, f], stable[s, f]) for s in IMPLICIT_SCHEMES)
        times = " / ".join(f"{row[s, f].us_per_throw:,.0f}" if stable[s, f] else "—"
                           for s in ("theta 0.5 + onset", "explicit"))
        lines.append(f"| {f:g} | {cells} | {times} |")
    onset = next(v for v in implicit.validation if v.theta == 0.5 and v.onset)
    return f"""\
**2. A linearly implicit contact** (`benchmarks/implicit_contact.py`: a prototype of one die of
the default scene, written for this study and not part of the package). Each step solves
`(M + θ dt C + θ² dt² K) dV = dt (F − θ dt K V)`. `K` and `C` are the 6×6 generalised
stiffness and damping of the corners in contact: normal springs, and tangential springs while
a corner sticks; slip is explicit Coulomb. θ = 1 is backward Euler; θ = 0.5 is the trapezoidal
rule. "+ onset" adds, on the next step, the impulse a corner missed in the step it crossed the
plane; the plain θ = 0.5 gains energy from that. The sample is {implicit.throws} gentle throws, \
the same face
at dt and dt/4 of the same scheme. Its validation at dt/4 of the default step: the θ = 0.5 +
onset variant has restitution {onset.restitution_1mps:.3f} (the explicit step's \
{implicit.explicit_restitution_1mps:.3f}) and gives the explicit
simulator's face in {100 * onset.faces_vs_explicit:.1f} % of throws.

| step / critical | backward Euler: e, faces | trapezoid: e, faces | trapezoid + onset: e, faces \
| explicit (same throws): e, faces | µs per throw: trapezoid + onset, explicit |
|---|---|---|---|---|---|
""" + "\n".join(lines) + "\n"


@generated("performance-mujoco-contact", limit=f"{STEP_LIMIT}#contact")
def performance_mujoco_contact(limit) -> str:
    """Table 3: MuJoCo's contact, default and stiff, against ours."""
    ours, mujoco = limit.ours, limit.mujoco
    rows = "\n".join(
        f"| MuJoCo, {name.replace('dt ', '')} | {m.dt_s * 1e6:,.0f} µs | "
        f"{m.landing['0.3'].restitution:.3f} | {m.landing['1.0'].restitution:.3f} | "
        f"{100 * m.landing['1.0'].sink:.2f} % | {m.throws_per_s_1thread:,.0f} | "
        f"{m.mean_rest_time_s:.2f} | {m.ours_vs_mujoco:.1f}× |" for name, m in mujoco.items())
    default, stiff = mujoco["default contact, dt 2 ms"], mujoco["stiff contact, dt timeconst/8"]
    return f"""\
**3. MuJoCo's contact and ours.** Flat, spin-free landings, and {limit.throws} hand throws to \
rest on one
thread, MuJoCo {limit.version}. MuJoCo's default contact is the setting `benchmarks/physics.py` \
times. The stiff
contact uses `solref` = ({limit.stiff_solref.timeconst_s:.3g} s, \
{limit.stiff_solref.dampratio:.3f}): the time constant and damping ratio of our
flat-landing mode `(m/4) x'' = −S x − D x'` at the table's restitution, set on both geoms
(MuJoCo mixes the two geoms' parameters).

| model | dt | e (0.3 m/s) | e (1 m/s) | sink at 1 m/s / edge | throws/s to rest | rest (s) | \
ours / it |
|---|---|---|---|---|---|---|---|
| ours, `Scene()`, early rest | {ours.dt_s * 1e6:.1f} µs | {ours.landing["0.3"].restitution:.3f} \
| {ours.landing["1.0"].restitution:.3f} | {100 * ours.landing["1.0"].sink:.2f} % | \
{ours.throws_per_s_1thread:,.0f} | {ours.mean_rest_time_s:.2f} | — |
{rows}

MuJoCo's default contact differs from the realistic table. The die does not bounce at all, and
on a 1 m/s flat landing it sinks {100 * default.landing["1.0"].sink:.0f} % of its edge, where the \
table asks for restitution about
0.45 and a sink of at most about 3 %. That soft contact is what lets MuJoCo take 2 ms steps.
Given a contact like ours (the same sink and about the same bounce), MuJoCo needs steps of
tens of µs, and we are {stiff.ours_vs_mujoco:.0f}× faster than MuJoCo at \
{stiff.dt_s * 1e6:.0f} µs.
"""


def median(values: list[float]) -> float:
    """The middle of ``values`` (the upper middle of an even count)."""
    return sorted(values)[len(values) // 2]


@generated("performance-kernel-ab", single="benchmarks/results/kernel_ab.json",
           groups="benchmarks/results/kernel_ab_groups.json",
           contact="benchmarks/results/kernel_ab_groups_contact.json")
def performance_kernel_ab(single, groups, contact) -> str:
    """Each A/B run of the kernel: a figure's median, base and this, and each round's ratio."""
    lines = ["| run | figure | base | this | this / base, per round |", "|---|---|---|---|---|"]
    for run in (single, groups, contact):
        for key, f in run.figures.items():
            same = run.same_faces if "same_faces" in run else run.bit_identical[key]
            outcomes = "same outcomes" if same is True else "outcomes differ"
            ratios = ", ".join(f"{x:.3f}" for x in f.ratios)
            lines.append(f"| `{run.command}`, {run.base_commit} → {run.commit}, {outcomes} | "
                         f"{key} | {median(f.base):,.4g} | {median(f.this):,.4g} | {ratios} |")
    return "\n".join(lines) + "\n"


UNTIL_WORDS = {"decided": "decided faces", "rest": "rest"}


@generated("performance-dice", dice="benchmarks/results/dice_together.json")
def performance_dice(dice) -> str:
    """Several dice: a group's throws/s against the single die's, a pair apart, MuJoCo."""
    rows, apart = dice.rows, dice.apart_pair
    table = markdown_table(
        "dice | to | ours (throws/s) | MuJoCo, default contact and 2 ms step (throws/s) | "
        "ours / MuJoCo",
        ((m.dice, UNTIL_WORDS[m.until], f"{m.ours.throws_per_s:,.1f}",
          f"{m.mujoco_default.throws_per_s:,.0f}", f"{m.mujoco_default.ours_vs_mujoco:.2f}")
         for m in dice.mujoco))
    return f"""\
A die in a group takes the single die's step on the planes (`kernel.die_on_planes`); around
it the group keeps per-die arrays and tests its pairs: one die in a group runs at \
{rows[0].throws_per_s:,.0f} throws/s against `simulate`'s {rows[1].throws_per_s:,.0f} on
the same throws, to decided faces on one thread (`{dice.command}`, \
`benchmarks/results/dice_together.json`). Two d6 into the tray run at \
{rows[3].throws_per_s:.1f} throws/s, six at {rows[4].throws_per_s:.1f} and twelve at \
{rows[5].throws_per_s:.2f}, in islands ("Islands" below): an island of several dice moves at \
the table's step while no pair of its dice can meet within it and at the die–die contact's \
(`dice_env.simulation.group.pair_step`, shorter: the pair's reduced mass) while one can. Two \
d6 {apart.spacing_m * 100:.0f} cm apart (they met in {apart.met:.0%} of {apart.throws} throws) \
cost {apart.pair_per_alone:.1f}× the CPU time of their two dice thrown alone: the group's rule \
for a decided face (no energy left in the throw can turn any die) waits for both dice, where \
each die alone stops at its own lock.

Against MuJoCo on the same releases into the tray, one thread, CPU time, to decided faces and
to rest (MuJoCo's rest: every corner slower than the rest speed for the hold, its contacts not
counted; the benchmark's docstring gives both rules):

{table}
"""


@generated("performance-islands", islands="benchmarks/results/islands.json")
def performance_islands(islands) -> str:
    """The several-dice tasks' throws in islands against stepped together."""
    table = markdown_table(
        "task | in islands (throws/s) | stepped together (throws/s) | ratio | same faces",
        ((f"`{r.task}`", f"{r.islands_throws_per_s:,.0f}", f"{r.together_throws_per_s:,.0f}",
          f"{r.islands_over_together:.2f}", f"{r.same_faces:.0%}") for r in islands.rows))
    return f"""\
The releases of the several-dice tasks' vector envs ({islands.rows[0].throws} seeded random \
actions a task, one thread, CPU time, best of {islands.repeats}; `{islands.command}`, \
`benchmarks/results/islands.json`), in islands and stepped together:

{table}
"""


# docs/benchmark.md

TUNING = "benchmarks/results/tuning.json"
BASELINES = "benchmarks/results/baselines.json"
LEARNED = "benchmarks/results/learned.json"


@generated("benchmark-tuning", t=TUNING, b=BASELINES)
def benchmark_tuning(t, b) -> str:
    """Each algorithm's variants in the search, and how the chosen ones spread over seeds."""
    rows = "\n".join(f"| {algo.upper()} | "
                     + ", ".join(f"{v.variant} {v.rate:.3f}" for v in variants) + " |"
                     for algo, variants in t.algos.items())
    spans = ", ".join(f"{a.upper()} {r.learned[a].min:.2f}–{r.learned[a].max:.2f}"
                      for r in b.rows if r.task == "DiceThrow-v0" for a in b.algos)
    return f"""\
| algorithm | variants: success on the search's {t.throws} throws (best first) |
|---|---|
{rows}

The search took {t.train_seconds / 3600:.1f} h of training CPU time. Each variant is one
run: a difference under about 0.07 (two 95 % intervals of 400 throws) is within the noise of
one seed, so the search separates only large effects, and it does not see how a variant
varies over seeds: on `DiceThrow-v0` the benchmark's 3 seeds of the chosen variants span
{spans}
(SAC's large learning rate learns fast on some seeds and not at all on others).
"""


def best_algorithm(row) -> str:
    """The algorithm with the best mean success over its seeds on a benchmark row."""
    return max(row.learned, key=lambda a: row.learned[a].mean)


@generated("benchmark-budget", b=BASELINES)
def benchmark_budget(b) -> str:
    """Each task's best algorithm along its budget: where it levels off, or not."""
    lines = []
    for row in b.rows:
        best = best_algorithm(row)
        curve = ", ".join(f"{p[2]:.2f} at {p[0]:,.0f}" for p in row.learned[best].curve)
        lines.append(f"- `{row.task}`, {row.budget:,} throws: {best.upper()}, {curve}")
    return f"""\
The best algorithm of each task (by its seeds' mean success), its seeds' mean success on
the curve's {b.curve_throws} fixed throws along the budget:

{chr(10).join(lines)}
"""


@generated("benchmark-summary", b=BASELINES)
def benchmark_summary(b) -> str:
    """Every task's success: random, the rule, each algorithm over its seeds, the oracle."""
    runs = [v for r in b.rows for v in r.learned.values()]
    lines = ["| task | budget (throws) | random | rule | "
             + " | ".join(a.upper() for a in b.algos) + " | oracle |",
             "|---" * (len(b.algos) + 5) + "|"]
    for r in b.rows:
        rule = " ".join(f"{r.fixed[k]:.2f}" for k in r.fixed
                        if k not in ("random", "oracle")) or "–"
        learned = " | ".join(
            f"{r.learned[a].mean:.2f} ± {r.learned[a].sd:.2f} [{r.learned[a].min:.2f}, "
            f"{r.learned[a].max:.2f}]" if a in r.learned else "–" for a in b.algos)
        lines.append(f"| `{r.task}` | {r.budget:,} | {r.fixed.random:.2f} | {rule} | {learned} "
                     f"| {r.fixed.oracle:.2f} |")
    return f"""\
Success of the policy's mean action on {b.final_throws} throws, mean ± sd over the seeds
[min, max]; random, the rule and the oracle from `benchmarks/results/tasks.json` (the oracle on its own
observations, see [named tasks](environment.md#named-tasks)). The {sum(len(v.seeds) for v in runs)} runs took
{sum(v.train_seconds for v in runs) / 3600:.1f} h of
training CPU time in all (the evaluations left out):

""" + "\n".join(lines) + "\n"  # noqa: E501


def signed(d) -> str:
    """A paired difference and its interval, three decimals."""
    return f"{d.diff:+.3f} [{d.ci[0]:+.3f}, {d.ci[1]:+.3f}]"


@generated("benchmark-learned", learned=LEARNED, b=BASELINES)
def benchmark_learned(learned, b) -> str:
    """Each task's best learned thrower against the oracle, its strategy and its sevens."""
    head = ("| task | learned | on the oracle's throws: learned / oracle | oracle − learned | "
            "release speed (m/s), learned / oracle | spin (rad/s), learned / oracle |")
    rows = [head, "|---|---|---|---|---|---|"]
    for t in learned.tasks:
        gap = t.oracle_minus_learned
        rows.append(
            f"| `{t.task}` | {t.algo.upper()} seed {t.seed}: {t.learned:.2f} | "
            f"{t.on_oracle_throws.learned.rate:.2f} / {t.on_oracle_throws.oracle.rate:.2f} | "
            f"{gap.diff:+.2f} [{gap.ci[0]:+.2f}, {gap.ci[1]:+.2f}] | "
            f"{t.release.learned.speed:.2f} / {t.release.oracle.speed:.2f} | "
            f"{t.release.learned.spin:.1f} / {t.release.oracle.spin:.1f} |")
    below = ", ".join(f"`{t.task}`" for t in learned.tasks
                      if t.oracle_minus_learned.ci[0] > 0) or "no task"
    matches = ", ".join(f"`{t.task}` ({signed(t.oracle_minus_learned)})" for t in learned.tasks
                        if t.oracle_minus_learned.ci[0] <= 0 <= t.oracle_minus_learned.ci[1]
                        ) or "no task at these budgets"
    best_runs = ", ".join(
        f"`{r.task}` " + max(((a.upper(), v.max) for a, v in r.learned.items()),
                             key=lambda p: p[1])[0]
        + f" {max(v.max for v in r.learned.values()):.2f} (oracle {r.fixed.oracle:.2f})"
        for r in b.rows)
    turns = ["| task | turn | learned: push, spin, axis | oracle: push, spin, axis | "
             "learned success |", "|---|---|---|---|---|"]
    for t in learned.tasks:
        for c in t.get("strategy", {}).get("learned", {}):
            mine, oracle = t.strategy.learned[c], t.strategy.oracle[c]
            success = f"{t.by_turn[c].rate:.2f} of {t.by_turn[c].n}" if c in t.by_turn else "–"
            turns.append(f"| `{t.task}` | {c} | {mine.push:.2f}, {mine.spin:.1f}, "
                         f"{mine.axis_cosine:.2f} | {oracle.push:.2f}, {oracle.spin:.1f}, "
                         f"{oracle.axis_cosine:.2f} | {success} |")
    voids = "; ".join(f"`{t.task}` " + ", ".join(f"{k} {v}" for k, v in t.void_reasons.items())
                      for t in learned.tasks)
    sevens = []  # one paragraph each
    for t in learned.tasks:
        for name in ("learned", "set") if "sevens" in t else ():
            thrower = ("the best learned, " + t.algo.upper() if name == "learned"
                       else "crossed set, 2 m/s at the back wall with backspin")
            s = t.sevens[name]
            noises = ", ".join(f"{r.noise:g}: {r.p:.3f} [{r.ci[0]:.3f}, {r.ci[1]:.3f}]"
                               for r in s.rows)
            largest = (f"{s.largest_noise_below:g}." if s.largest_noise_below is not None
                       else "none.")
            sevens.append(f"The {name} throw ({thrower}), {t.sevens.throws} throws per noise: "
                          f"{noises}; the largest noise at which the interval is wholly below "
                          f"1/6: {largest}\n")
    sevens_text = "\n".join(sevens)
    return """\
For each task, the best algorithm's best seed against the oracle searched from its actions
(`python -m agents.learned`; each task's commit in its entry): both scored on the same fresh
throws of the oracle's observations, the paired difference oracle − learned with its 95 %
interval, and the medians of what each asks for at release.

""" + "\n".join(rows) + f"""

Headroom: the best learned thrower is significantly below the oracle (the interval above 0) on
{below};
it matches it (the interval holds 0) on
{matches}.
The comparison takes the algorithm with the best mean over its seeds; the best single runs
(the summary's maxima) are {best_runs}.

One die, by how far the target must turn up (medians on the oracle's observations: `push`,
the horizontal speed along the roll that turns the target up; `spin`; `axis`, the cosine
between the spin axis and the axis that turns the target straight up), and the learned
thrower's success in each class on all its throws:

""" + "\n".join(turns) + f"""

How the learned throwers' {sum(learned.tasks[0].void_reasons.values())} evaluation throws per task
ended (a void throw is a failure): {voids}.

### Craps: P(seven) against the hand's noise

{sevens_text}
The noise is the hand's (`hand_noise` and `orientation_noise`, relative); the craps task
rewards avoiding a seven, so a thrower that has learned anything throws fewer sevens than 1/6. Each
interval stands alone (five noises, no correction for the comparisons): one interval just
clear of 1/6 among others that hold it is weak evidence.
"""


def spread(values, digits: int = 2) -> str:
    """``mean ± sd`` of a row's seeds; the mean alone for one seed."""
    return f"{values.mean:.{digits}f}" + (f" ± {values.sd:.{digits}f}" if values.sd else "")


@generated("benchmark-recipe", learned=LEARNED)
def benchmark_recipe(learned) -> str:
    """The recipe's rows per task, preset and method, their commands, those below 0.9 x oracle."""
    first = learned.recipe[0].runs[0]
    rows = [f"PPO: the policy's mean action on each run's {first.learned.n} throws; on the "
            "oracle's throws: PPO and the oracle on the same observations (the number in the "
            "column) × 16 throws each; mean ± sd over the seeds; CPU time of the training "
            "(for expert iteration also its searches and cloning), all seeds together (two "
            "shared cores); the budget counts every simulated throw of the training; the task's "
            "rule and random actions on the oracle's throws as fractions of the oracle's "
            "success (means over the seeds; – where the row's runs did not keep them):", "",
            "| task | method, preset, budget (throws) | seeds | PPO | on the oracle's throws: "
            "PPO / oracle (observations) | PPO / oracle | rule, random / oracle | "
            "training CPU time |",
            "|---|---|---|---|---|---|---|---|"]
    for r in learned.recipe:
        base = getattr(r, "baseline_ratios", None)
        others = (", ".join(f"{getattr(base, name).mean:.2f}" if hasattr(base, name) else "–"
                            for name in ("rule", "random")) if base is not None else "–")
        rows.append(f"| `{r.task}` | {_method(r)}, {r.throws:,} | {len(r.seeds)} | "
                    f"{spread(r.learned)} | {spread(r.ppo_on_oracle_throws)} / "
                    f"{spread(r.oracle)} ({r.runs[0].observations}) | {spread(r.ratio)} | "
                    f"{others} | {r.cpu_seconds / 60:.0f} min |")
    commands = [f"- `{r.task}`, {_method(r)}: `{r.command}`" for r in learned.recipe]
    below = "; ".join(
        f"`{r.task}` ({_method(r)}) {r.ratio.mean:.2f}, PPO − oracle "
        f"{sum(run.learned_minus_oracle.diff for run in r.runs) / len(r.runs):+.3f}"
        for r in learned.recipe if r.ratio.mean < 0.9) or "no task"
    labels = [
        f"`{r.task}` ({_method(r)}): labels "
        f"{_mean(run.expert.rounds[-1].labels_on_fresh_draws for run in r.runs):.3f} against "
        f"the policy's {_mean(run.expert.rounds[-1].policy_on_fresh_draws for run in r.runs):.3f}"
        f" ({r.runs[0].expert.rounds[-1].observations} observations per seed, "
        f"{_mean(run.expert.rounds[-1].labels_moved for run in r.runs):.0%} of the labels moved "
        "from the policy's action)"
        for r in learned.recipe if getattr(r, "method", "recipe") != "recipe"]
    searched = ([f"Expert iteration's labels against the policy they were searched from, on 8 "
                 f"fresh throws of each labelled observation (the last round, mean over the "
                 f"seeds): {'; '.join(labels)}.", ""] if labels else [])
    return "\n".join([*rows, "", "Each row's command (S: the seed):", "", *commands, "",
                      *searched,
                      "Below 0.9 × the oracle on its throws (PPO / oracle, and the paired "
                      f"difference in success on the same throws, mean over the seeds): {below}."])


def _mean(values) -> float:
    """The mean of an iterable of numbers."""
    values = list(values)
    return sum(values) / len(values)


def _method(row) -> str:
    """A recipe row's preset, with its method where it is not the plain recipe."""
    method = getattr(row, "method", "recipe")
    return row.preset if method == "recipe" else f"{row.preset} + {method}"


@generated("benchmark-sharpness", learned=LEARNED)
def benchmark_sharpness(learned) -> str:
    """The oracle's success as the hand turns and as its action moves, per one-die task."""
    first = learned.sharpness[0]
    head = ("| task | " + " | ".join(f"hand turned {t.degrees:g}°" for t in first.turned)
            + " | " + " | ".join(f"action moved {m.step:g}" for m in first.moved) + " |")
    rows = [f"On {first.observations} observations, {first.samples} noise draws each:", "",
            head, "|---" * (1 + len(first.turned) + len(first.moved)) + "|"]
    rows += [f"| `{r.task}` | " + " | ".join(f"{t.rate:.2f}" for t in r.turned) + " | "
             + " | ".join(f"{m.rate:.2f}" for m in r.moved) + " |" for r in learned.sharpness]
    kept = "; ".join(
        f"`{r.task}` keeps {r.turned[3].rate / r.turned[0].rate:.0%} of its oracle's success "
        f"with the hand turned {r.turned[3].degrees:g}° and "
        f"{r.moved[1].rate / r.turned[0].rate:.0%} with the action moved {r.moved[1].step:g}"
        for r in learned.sharpness)
    return "\n".join([*rows, "", f"{kept}."])

