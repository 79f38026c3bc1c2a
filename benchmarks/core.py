"""The integration step: geojax's step against the smallest kernel that does the same work, and against an
earlier revision of geojax, in one run.

    python benchmarks/core.py [--baseline REV ...] [--batches 1 64 1024 4096] [--cycles 4] [--loop-days 20]

Per implementation and batch: nanoseconds per right-hand-side evaluation per sample (4 per RK4 step),
orbit-years per second, and the fusions of the compiled step (the loop body's ``fusion`` instructions and
the conditionals that ``physics.fusion.materialized`` adds, counted in ``compile().as_text()``).  Then the
closed loop (li2022-qffc and li2022-fompc, H = 1 errors, batch 256): simulated years per second.

* ``geojax``: this working tree, ``jit(vmap(loop.simulate.propagate))`` with the li2022 force model with
  C22/S22 and the conical shadow on, MEE, 897.5 s step (96 per sidereal day);
* ``geojax@REV``: the same measurement of each pinned revision REV, run in a subprocess from a temporary
  ``git worktree``, one after the other on the same machine.  Default: the issue's baseline (the commit
  before the fused step) and the step before its plain-arithmetic cos and sin (``physics.trig``);
* ``minimal``: Cartesian RK4 written straight in jax.numpy on component arrays: point mass, J2, Sun and
  Moon (from the same environment grid), SRP without shadow; no C22, no records, no cycle means.

Every implementation runs on one device pinned to one core (``harness.Devices``: one XLA CPU device, the
user's other ``XLA_FLAGS`` kept, the process pinned to the lowest core it may use):
the comparison is per core, not how well each shards or how far XLA spreads one kernel over idle cores (on
one unpinned device the issue's baseline, whose kernels are few and large, drew a second core that the
fused step's many small kernels do not; and a second core shared with other work made every number move).
A sweep runs one such device per core (``geojax.parallel.per_device``).  Results:
``benchmarks/results/core.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import tempfile
import time
from pathlib import Path

import harness

HERE = Path(__file__).resolve().parent
LOOP_ROUNDS = 3  # closed-loop runs per controller, the fastest kept
DEFAULT_BASELINES = ("1c1acb7",  # main before the fused step: issue 13's baseline
                     "1ea0b52")  # main before cos L, sin L in plain arithmetic (physics.trig)


def measure_engine(batches, n_cycles: int, loop_days: float) -> dict:
    """This process's geojax: the step (uncontrolled, via the one loop) and the closed loop."""
    return {"step": _step_rows({"forces.c22_s22": True}, batches, n_cycles), "loop": _closed_loop(loop_days) if loop_days else {}}


def _step_rows(overrides: dict, batches, n_cycles: int, timed=None) -> dict:
    """The uncontrolled step of li2022 with ``overrides``, per batch: ``_timed_step``'s row (or ``timed``'s)."""
    import jax
    import jax.numpy as jnp

    import geojax  # noqa: F401  (x64)
    from geojax import scenario
    from geojax.loop.simulate import propagate
    from geojax.physics.constants import SIDEREAL_DAY_S
    from geojax.physics.dynamics import SpacecraftState
    from geojax.physics.propagate import MEE, environment_grid, steps_per_cycle

    sc = scenario.load("li2022", overrides)
    n_steps = steps_per_cycle(sc.step_s)
    step_s = SIDEREAL_DAY_S / n_steps
    env = environment_grid(sc.epoch_tt_s, sc.epoch_tt_s, sc.tt_minus_ut1_s, step_s, n_cycles, n_steps)
    fm = jax.tree_util.tree_map(jnp.asarray, sc.force_model)
    try:
        from geojax.physics.propagate import for_lanes
    except ImportError:  # a revision before the fused step
        for_lanes = lambda dynamics, lanes: dynamics  # noqa: E731
    rows = {}
    for batch in batches:
        mee = jnp.broadcast_to(jnp.asarray(sc.initial_mee), (batch, 6))
        mass = jnp.full(batch, sc.mass_kg)
        dynamics = for_lanes(MEE, batch)
        run = jax.jit(jax.vmap(lambda m, kg, d=dynamics: propagate(d, SpacecraftState(m, kg, jnp.asarray(0.0)), env,
                                                                  fm, step_s)[0].orbit))
        rows[batch] = (timed or _timed_step)(run, (mee, mass), batch, n_cycles * n_steps, step_s)
    return rows


# The Earth's field (``physics.geopotential``) in the li2022 step, beside the papers' J2 + C22/S22.
FIELD_MODELS = {"J2 + C22/S22": {"forces.c22_s22": True}, "EGM2008 2x2": {"forces.gravity_degree": 2},
                "EGM2008 8x8": {"forces.gravity_degree": 8}, "EGM2008 20x20": {"forces.gravity_degree": 20}}


FIELD_REPEATS = 30  # timed runs of each model, the models alternating


def measure_field_papers(batches, n_cycles: int) -> dict:
    """``measure_field`` of the papers' J2 + C22/S22 step alone (``--field-baseline``: another tree's)."""
    return measure_field(batches, n_cycles, {"J2 + C22/S22": FIELD_MODELS["J2 + C22/S22"]})


def measure_field(batches, n_cycles: int, models: dict = FIELD_MODELS) -> dict:
    """The step with each force model of ``models`` (``--field``): every model compiled first, then
    ``FIELD_REPEATS`` runs of each in turn, the fastest kept (on a shared machine the load moves within a
    model's own runs; alternating lets every model meet the same quiet moments)."""
    import jax

    pending = {}

    def compiled(fn, args, batch, n_steps_total, step_s):
        start = time.perf_counter()
        exe = fn.lower(*args).compile()
        compile_s = time.perf_counter() - start
        jax.block_until_ready(exe(*args))  # warm
        return {"exe": exe, "args": args, "best": float("inf"), "batch": batch, "n": n_steps_total,
                "step_s": step_s, "row": {"compile_s": compile_s, **step_fusions(exe.as_text())}}

    for name, overrides in models.items():
        pending[name] = _step_rows(overrides, batches, n_cycles, timed=compiled)
    for _ in range(FIELD_REPEATS):
        for rows in pending.values():
            for run in rows.values():
                start = time.perf_counter()
                jax.block_until_ready(run["exe"](*run["args"]))
                run["best"] = min(run["best"], time.perf_counter() - start)
    return {"step": {name: {batch: {"ns_per_rhs_per_sample": run["best"] / (4 * run["batch"] * run["n"]) * 1e9,
                                    "orbit_years_per_s": run["batch"] * run["n"] * run["step_s"] / 86400 / 365.25
                                    / run["best"], **run["row"]}
                            for batch, run in rows.items()}
                     for name, rows in pending.items()}}


def _timed_step(fn, args, batch: int, n_steps_total: int, step_s: float) -> dict:
    compiled, compile_s = harness.compile_jitted(fn, *args)
    text = compiled.as_text()
    _, timing = harness.measure(compiled, *args, repeats=3, warmup=1)
    best = timing.best_s
    return {"ns_per_rhs_per_sample": best / (4 * batch * n_steps_total) * 1e9,
            "orbit_years_per_s": batch * n_steps_total * step_s / 86400 / 365.25 / best,
            "compile_s": compile_s, **step_fusions(text)}


def step_fusions(hlo_text: str) -> dict:
    """Fusions and conditionals of the compiled step: the computation with the most fusions is the step's
    loop body; its conditionals' branches are counted with it."""
    computations = {m.group(1): m.group(2) for m in re.finditer(r"\n(%[\w.\-]+) [^\n]*\{\n(.*?)\n\}", hlo_text, re.S)}
    body_name = max(computations, key=lambda name: computations[name].count(" fusion("))
    body = computations[body_name]
    branches = re.findall(r"branch_computations=\{([^}]*)\}", body)
    branch_fusions = sum(computations.get(name.strip(), "").count(" fusion(")
                         for group in branches for name in group.split(","))
    return {"fusions_per_step": body.count(" fusion(") + branch_fusions,
            "conditionals_per_step": body.count(" conditional(")}


def _closed_loop(days: float, batch: int = 256) -> dict:
    import jax
    import jax.numpy as jnp

    from geojax import scenario
    from geojax.runner.rollout import rollout_fn
    from geojax.runner.setup import prepare

    compiled = {}
    for controller in ("qffc", "fompc"):
        sc = scenario.load(f"li2022-{controller}", {"duration.days": days, "errors.h_rv": 1.0, "errors.h_att": 1.0})
        setup = prepare([sc])
        try:
            one = rollout_fn(setup, lanes=batch)
        except TypeError:  # a revision before the fused step
            one = rollout_fn(setup)
        run = jax.jit(jax.vmap(lambda p, k: one(p, k)[2]))
        params = jax.tree_util.tree_map(lambda x: jnp.broadcast_to(x[0], (batch,) + x.shape[1:]), setup.params)
        keys = jax.vmap(lambda i: jax.random.fold_in(jax.random.key(0), i))(jnp.arange(batch))
        compiled[controller] = (run.lower(params, keys).compile(), (params, keys),
                                batch * setup.n_cycles * 86164.0905 / (365.25 * 86400))
    # Best of LOOP_ROUNDS runs of each, the controllers alternating (the machine may be shared).
    out, walls = {}, {controller: [] for controller in compiled}
    for _ in range(LOOP_ROUNDS + 1):  # the first round warms up
        for controller, (fn, args, years) in compiled.items():
            start = time.perf_counter()
            metrics = jax.block_until_ready(fn(*args))
            walls[controller].append(time.perf_counter() - start)
            out[controller] = {"batch": batch, "days": days, "rounds": LOOP_ROUNDS,
                               "mean_dv_per_year_mps": float(jnp.mean(metrics["dv_per_year_mps"]))}
    for controller, (_, _, years) in compiled.items():
        out[controller]["years_per_s"] = years / min(walls[controller][1:])
    return out


def measure_minimal(batches, n_cycles: int) -> dict:
    """The smallest kernel of the same work (see the module docstring)."""
    import jax
    import jax.numpy as jnp

    import geojax  # noqa: F401
    from geojax import scenario
    from geojax.physics import constants as c
    from geojax.physics.constants import SIDEREAL_DAY_S
    from geojax.physics.elements import mee_to_cartesian
    from geojax.physics.propagate import environment_grid, steps_per_cycle

    sc = scenario.load("li2022")
    fm = sc.force_model
    n_steps = steps_per_cycle(sc.step_s)
    h = SIDEREAL_DAY_S / n_steps
    env = environment_grid(sc.epoch_tt_s, sc.epoch_tt_s, sc.tt_minus_ut1_s, h, n_cycles, n_steps)
    suns, moons = env.r_sun_eci_m.reshape(-1, 3, 3), env.r_moon_eci_m.reshape(-1, 3, 3)
    srp = fm.srp_pressure_1au_n_m2 * (1 + fm.reflectivity) * fm.srp_area_m2 / sc.mass_kg * c.AU_M**2

    def rhs(s, sun, moon):
        x, y, z, vx, vy, vz = s
        r2 = x * x + y * y + z * z
        ir3 = 1 / (r2 * jnp.sqrt(r2))
        j2 = 1.5 * fm.j2 * fm.r_earth_m**2 / r2
        q = j2 * (5 * z * z / r2 - 1)
        ax = -fm.mu_m3_s2 * ir3 * x * (1 - q)
        ay = -fm.mu_m3_s2 * ir3 * y * (1 - q)
        az = -fm.mu_m3_s2 * ir3 * z * (1 - q - 2 * j2)
        for body, mu in ((sun, fm.mu_sun_m3_s2), (moon, fm.mu_moon_m3_s2)):
            dx, dy, dz = body[0] - x, body[1] - y, body[2] - z
            d2 = dx * dx + dy * dy + dz * dz
            k = mu / (d2 * jnp.sqrt(d2))
            b2 = body[0] ** 2 + body[1] ** 2 + body[2] ** 2
            kb = mu / (b2 * jnp.sqrt(b2))
            ax, ay, az = ax + k * dx - kb * body[0], ay + k * dy - kb * body[1], az + k * dz - kb * body[2]
        dx, dy, dz = sun[0] - x, sun[1] - y, sun[2] - z
        d2 = dx * dx + dy * dy + dz * dz
        k = srp / (d2 * jnp.sqrt(d2))
        return (vx, vy, vz, ax - k * dx, ay - k * dy, az - k * dz)

    def step(s, xs):
        sun3, moon3 = xs
        k1 = rhs(s, sun3[0], moon3[0])
        k2 = rhs(tuple(a + h / 2 * b for a, b in zip(s, k1)), sun3[1], moon3[1])
        k3 = rhs(tuple(a + h / 2 * b for a, b in zip(s, k2)), sun3[1], moon3[1])
        k4 = rhs(tuple(a + h * b for a, b in zip(s, k3)), sun3[2], moon3[2])
        return tuple(a + h / 6 * (b + 2 * c_ + 2 * d + e) for a, b, c_, d, e in zip(s, k1, k2, k3, k4)), None

    def run_one(rv):
        final, _ = jax.lax.scan(step, tuple(rv[i] for i in range(6)), (suns, moons))
        return jnp.stack(final)

    r, v = mee_to_cartesian(jnp.asarray(sc.initial_mee), fm.mu_m3_s2)
    rows = {}
    for batch in batches:
        rv = jnp.broadcast_to(jnp.concatenate([r, v]), (batch, 6))
        rows[batch] = _timed_step(jax.jit(jax.vmap(run_one)), (rv,), batch, n_cycles * n_steps, h)
    return {"step": rows}


def _keep_fastest(rows: dict, measured: dict) -> None:
    for batch, row in measured.items():
        if batch not in rows or row["ns_per_rhs_per_sample"] < rows[batch]["ns_per_rhs_per_sample"]:
            rows[batch] = row


def one_core(platform: str | None = None) -> harness.Devices:
    """One device on one core (the lowest this process may use): what every implementation is measured on."""
    return harness.Devices(host_device_count=1, replace_count=True, platform=platform,
                           cores=harness.usable_cores()[:1])


def _in_subprocess(tree: Path, what: str, args, loop: bool = True) -> dict:
    """Run one measurement in a fresh Python on ``tree``'s geojax (one device pinned to one core, nothing
    else loaded)."""
    code = (f"import json, sys; sys.path.insert(0, {str(HERE)!r}); import core; "
            f"print(json.dumps(core.{what}({args.batches!r}, {args.cycles}"
            f"{', ' + repr(args.loop_days if loop else 0.0) if what == 'measure_engine' else ''})))")
    return harness.run_json(["-c", code], one_core(args.platform), cwd=tree, pythonpath=tree)


def markdown(results: dict) -> list[str]:
    impls = list(results["step"])
    lines = ["One device pinned to one core per implementation, li2022 force model (C22/S22 and conical shadow on; "
             "the minimal kernel without C22 and shadow), 96 steps per sidereal day, "
             f"{results['cycles']} cycles, the fastest of {results.get('rounds', 1)} alternating rounds. ns per "
             "right-hand side per sample (4 per RK4 step), orbit-years/s, fusions (and conditionals) of the "
             "compiled step.", "",
             *harness.table(["batch", *impls], [[batch, *(_cell(results["step"][impl][str(batch)]) for impl in impls)]
                                               for batch in results["batches"]], align="r" * (1 + len(impls)))]
    lines += ["", "Cost per right-hand side relative to the minimal kernel: " + "; ".join(
        f"batch {batch}: " + ", ".join(f"{impl} {_relative(results, impl, batch):.2f}x" for impl in impls[:-1])
        for batch in results["batches"]) + "."]
    looped = [k for k in impls if results["loop"].get(k)]
    if not looped:  # --loop-days 0
        return lines
    lines += ["", "Closed loop, batch 256, H = 1 errors, li2022 scenarios over "
              f"{_loop_days(results)} days: simulated years per second, the fastest of {LOOP_ROUNDS} runs "
              "alternating the controllers (mean ΔV, m/s/yr).", ""]
    lines += harness.table(["controller", *looped],
                           [[controller, *(f"{results['loop'][k][controller]['years_per_s']:.2f} "
                                           f"({results['loop'][k][controller]['mean_dv_per_year_mps']:.3f})"
                                           for k in looped)] for controller in ("qffc", "fompc")])
    return lines


def _cell(row: dict) -> str:
    return (f"{row['ns_per_rhs_per_sample']:.1f} ns, {row['orbit_years_per_s']:.0f} /s, {row['fusions_per_step']} "
            f"({row['conditionals_per_step']})")


def _loop_days(results: dict) -> str:
    days = {row["days"] for loop in results["loop"].values() for row in loop.values()}
    return ", ".join(f"{d:g}" for d in sorted(days))


def _relative(results: dict, impl: str, batch: int) -> float:
    ns = lambda name: results["step"][name][str(batch)]["ns_per_rhs_per_sample"]  # noqa: E731
    return ns(impl) / ns("minimal")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", nargs="*", default=list(DEFAULT_BASELINES),
                        help="git revisions to compare with (none: --baseline with no value)")
    parser.add_argument("--batches", type=int, nargs="+", default=[1, 64, 1024, 4096])
    parser.add_argument("--cycles", type=int, default=4, help="sidereal days per step measurement")
    parser.add_argument("--loop-days", type=float, default=20.0, help="days of the closed-loop measurement")
    parser.add_argument("--rounds", type=int, default=2, help="alternating rounds of the step measurement")
    parser.add_argument("--field", action="store_true",
                        help="only the Earth's field: J2 + C22/S22, EGM2008 2x2, 8x8, 20x20 and the minimal kernel "
                             "(results/core_field.json and .md)")
    harness.add_arguments(parser)
    parser.add_argument("--field-baseline", metavar="REV",
                        help="with --field: also the J2 + C22/S22 step of revision REV, in the same rounds")
    args = parser.parse_args()
    run = harness.start(one_core(args.platform))
    repo = HERE.parent
    if args.field:
        return field_only(args, run, repo)
    results = {"batches": args.batches, "rounds": args.rounds, "cycles": args.cycles, "step": {}, "loop": {}}
    runs = [("geojax", repo)]
    with tempfile.TemporaryDirectory() as tmp:
        for rev in args.baseline:
            old = Path(tmp) / rev
            subprocess.run(["git", "-C", str(repo), "worktree", "add", "--detach", str(old), rev],
                           check=True, capture_output=True)
            runs.append((f"geojax@{rev}", old))
        try:
            # Rounds alternate the implementations (the machine may be shared); each batch keeps its fastest
            # round.  The closed loop is measured in the first round.
            for round_ in range(args.rounds):
                for name, tree in runs:
                    print(f"{name} (round {round_ + 1}) ...", flush=True)
                    measured = _in_subprocess(tree, "measure_engine", args, loop=round_ == 0)
                    _keep_fastest(results["step"].setdefault(name, {}), measured["step"])
                    if round_ == 0:
                        results["loop"][name] = measured["loop"]
        finally:
            for _, tree in runs[1:]:
                subprocess.run(["git", "-C", str(repo), "worktree", "remove", "--force", str(tree)], check=False)
    for round_ in range(args.rounds):
        print(f"minimal (round {round_ + 1}) ...", flush=True)
        _keep_fastest(results["step"].setdefault("minimal", {}), _in_subprocess(repo, "measure_minimal", args)["step"])
    print(harness.write(args.out / "core", run, "The integration step", results, markdown(results)))


def field_only(args, run: harness.Run, repo: Path) -> None:
    """``--field``: the step with each of ``FIELD_MODELS`` and the minimal kernel, alternating rounds."""
    results = {"batches": args.batches, "rounds": args.rounds, "cycles": args.cycles, "step": {}}
    with tempfile.TemporaryDirectory() as tmp:
        old = Path(tmp) / "baseline"
        if args.field_baseline:
            subprocess.run(["git", "-C", str(repo), "worktree", "add", "--detach", str(old), args.field_baseline],
                           check=True, capture_output=True)
        try:
            for round_ in range(args.rounds):
                print(f"round {round_ + 1} ...", flush=True)
                for name, rows in _in_subprocess(repo, "measure_field", args)["step"].items():
                    _keep_fastest(results["step"].setdefault(name, {}), rows)
                if args.field_baseline:
                    _keep_fastest(results["step"].setdefault(f"J2 + C22/S22 @{args.field_baseline}", {}),
                                  _in_subprocess(old, "measure_field_papers", args)["step"]["J2 + C22/S22"])
                _keep_fastest(results["step"].setdefault("minimal", {}),
                              _in_subprocess(repo, "measure_minimal", args)["step"])
        finally:
            if args.field_baseline:
                subprocess.run(["git", "-C", str(repo), "worktree", "remove", "--force", str(old)], check=False)
    lines = ["One device pinned to one core, li2022 with each "
             "field (Sun, Moon, SRP and conical shadow on), MEE RK4, 96 steps per sidereal day, "
             f"{args.cycles} cycles, the fastest of {args.rounds} rounds (each model in turn, then the next "
             "round).  ns per right-hand side per sample; in brackets: relative to J2 + C22/S22 of this tree; "
             "compile s; fusions (conditionals) of the compiled step.", "",
             "| batch | " + " | ".join(results["step"]) + " |", "|---:|" + "---:|" * len(results["step"])]
    for batch in args.batches:
        base = results["step"]["J2 + C22/S22"][str(batch)]["ns_per_rhs_per_sample"]
        cells = [f"{r[str(batch)]['ns_per_rhs_per_sample']:.1f} ns ({r[str(batch)]['ns_per_rhs_per_sample'] / base:.2f}x), "
                 f"{r[str(batch)]['compile_s']:.1f} s, {r[str(batch)]['fusions_per_step']} "
                 f"({r[str(batch)]['conditionals_per_step']})" for r in results["step"].values()]
        lines.append(f"| {batch} | " + " | ".join(cells) + " |")
    print(harness.write(args.out / "core_field", run, "The Earth's field in the step", results, lines))


if __name__ == "__main__":
    main()
