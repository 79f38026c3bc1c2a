"""geojax on whatever devices JAX finds (a GPU where there is one), in one run: the engine against the
minimal kernel, ``geojax sweep`` at its automatic width, and the gap between the two.

    python benchmarks/accelerator.py [--quick]

On the platform of ``jax.devices()[0]`` (named in the results):

1. **Uncontrolled step**: the minimal Cartesian RK4 kernel of the same physics (``benchmarks/core.py``'s
   ``measure_minimal``: point mass, J2, Sun, Moon, SRP) against geojax's uncontrolled rollout (controller
   ``none``: ``simulate_batch``'s compiled batch run alone, records and metrics included, keys from one
   ``jax.random.split``), orbit-years per second after compilation, batches up to ``--batches``;
2. **Sweeps**: ``geojax.sweep.run_sweep`` of li2022-qffc, -fompc and -mpc (H_rv = H_att = 1) at the
   automatic width (``geojax.lanes``), sample-years per second with compilation and after it, the width it
   chose, and the device's peak memory (an accelerator's allocator statistics; the process's peak resident
   set on a CPU);
3. **The command line against the engine**: the same QFFC samples through ``simulate_batch`` (one compiled
   call, keys ``fold_in(key(seed), j)`` as the sweep draws them), and the mean Delta-V of both;
4. **Host work**: ``simulate_batch(..., seeds=range(100_000))`` (one cycle, controller ``none``): the seconds
   outside the compiled call (the call's wall less the same compiled executable run alone).

Results: ``benchmarks/results/accelerator_<platform>.json`` and ``.md`` (a CPU run does not overwrite a GPU
run's).  On a CPU the sizes are small (a few minutes on 2 cores); ``--quick`` smaller still.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import harness

SIDEREAL_YEAR_FRACTION = 86164.0905 / (365.25 * 86400)  # years per cycle

# (samples, days) per controller: the GPU sizes, and what 2 CPU cores finish in minutes.
SIZES = {"gpu": {"qffc": (131_072, 365.25), "fompc": (8192, 30.0), "mpc": (2048, 10.0)},
         "cpu": {"qffc": (1024, 30.0), "fompc": (128, 10.0), "mpc": (16, 4.0)}}
STEP_BATCHES = {"gpu": [4096, 16_384, 65_536, 131_072], "cpu": [256, 1024]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a tenth of the samples (a check that it runs)")
    parser.add_argument("--batches", type=int, nargs="+", help="step batches (default: the platform's)")
    parser.add_argument("--controllers", nargs="+", default=["qffc", "fompc", "mpc"])
    parser.add_argument("--host-only", action="store_true",
                        help="the host-work part alone, profiled (results: accelerator_<platform>_host)")
    harness.add_arguments(parser)
    args = parser.parse_args()
    run = harness.start(harness.Devices(platform=args.platform))  # one XLA CPU device per core (no effect on a GPU)
    import jax

    platform = "cpu" if jax.devices()[0].platform == "cpu" else "gpu"
    scale = 10 if args.quick else 1
    sizes = {c: (max(16, n // scale), days) for c, (n, days) in SIZES[platform].items() if c in args.controllers}
    batches = args.batches or [max(16, b // scale) for b in STEP_BATCHES[platform]]
    results = {"sweeps": {}}
    stem = f"accelerator_{platform}" + ("_host" if args.host_only else "")

    def save() -> str:  # after every part: a run cut short by a time limit keeps what it measured
        return harness.write(args.out / stem, run, f"geojax on {harness.facts()['device']}", results,
                             markdown(results))

    if args.host_only:
        results["host_keys"] = measure_host_keys(10_000 if args.quick else 100_000, profile=True)
        print(save())
        return

    # the headline first (the QFFC sweep), then the rest in order of what they tell
    for controller in [c for c in ("qffc", "fompc", "mpc") if c in sizes][:1]:
        results["sweeps"][controller] = measure_sweep(controller, *sizes[controller])
        save()
    results["step"] = measure_step(batches)
    save()
    if "qffc" in sizes:
        results["engine_qffc"] = measure_engine("qffc", *sizes["qffc"])
        save()
    for controller in [c for c in ("fompc", "mpc") if c in sizes]:
        results["sweeps"][controller] = measure_sweep(controller, *sizes[controller])
        save()
    results["host_keys"] = measure_host_keys(10_000 if args.quick else 100_000)
    print(save())


def measure_step(batches) -> dict:
    """Orbit-years/s of the minimal kernel and of geojax's uncontrolled rollout (controller ``none``, the
    compiled batch of ``simulate_batch`` run alone, records and metrics included), per batch."""
    import core

    from geojax import scenario

    n_cycles = 4
    rows = {}
    for batch in batches:
        minimal = core.measure_minimal([batch], n_cycles)["step"][batch]
        sc = scenario.load("li2022-qffc", {"controller.kind": "none", "duration.days": n_cycles})
        compiled, args = _compiled_rollouts(sc, batch)
        _, timing = harness.measure(compiled, *args, repeats=3, warmup=1)
        years = batch * n_cycles * SIDEREAL_YEAR_FRACTION
        rows[batch] = {"minimal_orbit_years_per_s": minimal["orbit_years_per_s"],
                       "geojax_orbit_years_per_s": years / timing.best_s,
                       "ratio_to_minimal": years / timing.best_s / minimal["orbit_years_per_s"]}
        print(f"step, batch {batch}: geojax {years / timing.best_s:.4g} orbit-years/s, minimal "
              f"{minimal['orbit_years_per_s']:.4g} ({rows[batch]['ratio_to_minimal']:.2f}x)", flush=True)
    return rows


def _compiled_rollouts(sc, n: int, keys=None):
    """``simulate_batch``'s compiled executable for ``n`` copies of ``sc`` and its arguments."""
    import jax

    from geojax.runner import rollout

    batch = rollout.prepare([sc])
    params = rollout.prepare_params(sc, n)
    keys = jax.random.split(jax.random.key(0), n) if keys is None else keys
    static = dict(controller=batch.controller, step_s=batch.step_s, dynamics=rollout.for_lanes(batch.dynamics, n),
                  keep_steps=False)
    args = (params, keys, batch.shared, rollout._reference_env(batch))
    compiled, _ = harness.compile_jitted(rollout.closed_loop_batch, *args, **static)
    return compiled, args


def measure_sweep(controller: str, samples: int, days: float) -> dict:
    import jax

    import sweep as sweep_benchmark  # its sweep file: li2022-<controller>, H_rv = H_att = 1, beta_max 70 deg

    from geojax import sweep

    spec = sweep_benchmark.sweep_spec(controller, samples, days)
    width = sweep.lane_plan(spec, controller)
    done = sweep_benchmark.run_sweep_file(spec)
    years = samples * round(days * 86400 / 86164.0905) * SIDEREAL_YEAR_FRACTION
    wall_s, compile_s = done["wall_s"], float(done["attrs"]["compile_s"])
    row = {"samples": samples, "days": days, "lanes_per_device": width.lanes, "lanes_source": width.source,
           "model_bytes_per_lane": width.bytes_per_lane, "wall_s": wall_s, "compile_s": compile_s,
           "sample_years_per_s": years / wall_s, "run_sample_years_per_s": years / (wall_s - compile_s),
           "peak_memory_gb": harness.peak_memory_bytes(jax.devices()[0]) / 1e9,
           "mean_dv_per_year_mps": float(done["metrics"]["dv_per_year_mps"].mean()),
           "status_ok_fraction": float((done["status"]["code"] == 0).mean())}
    print(f"sweep {controller}: {samples} x {days:g} days at {width.lanes} lanes: {row['sample_years_per_s']:.4g} "
          f"sample-years/s ({row['run_sample_years_per_s']:.4g} after compilation)", flush=True)
    return row


def measure_engine(controller: str, samples: int, days: float) -> dict:
    """The sweep's samples (one grid point, keys fold_in(key(7), j)) through ``simulate_batch`` in one call."""
    import jax
    import jax.numpy as jnp

    from geojax import scenario
    from geojax.runner.rollout import prepare_params, simulate_batch

    sc = scenario.load(f"li2022-{controller}", {"duration.days": days, "errors.h_rv": 1.0, "errors.h_att": 1.0,
                                                "thrusters.beta_max_deg": 70.0})
    params = prepare_params(sc, samples)
    keys = jax.vmap(lambda j: jax.random.fold_in(jax.random.key(7), j))(jnp.arange(samples))
    compiled = []
    result, call = harness.timed(simulate_batch, sc, params, keys=keys, on_compiled=compiled.append)
    years = samples * round(days * 86400 / 86164.0905) * SIDEREAL_YEAR_FRACTION
    row = {"samples": samples, "days": days, "wall_s": call.wall_s, "compile_s": compiled[0],
           "run_sample_years_per_s": years / (call.wall_s - compiled[0]),
           "mean_dv_per_year_mps": float(result.metrics["dv_per_year_mps"].mean())}
    print(f"simulate_batch {controller}: {row['run_sample_years_per_s']:.4g} sample-years/s after compilation",
          flush=True)
    return row


def measure_host_keys(n: int, profile: bool = False) -> dict:
    """Seconds of ``simulate_batch(seeds=range(n))`` outside its compiled call (one cycle, no controller);
    ``profile``: and where they go (one more call under ``cProfile``: the functions of geojax with the most
    cumulative time)."""
    from geojax import scenario
    from geojax.runner.rollout import keys_of, prepare_params, simulate_batch

    sc = scenario.load("li2022-qffc", {"controller.kind": "none", "duration.days": 1})
    params = prepare_params(sc, n)
    _, whole = harness.measure(simulate_batch, sc, params, repeats=3, warmup=1, seeds=range(n))
    compiled, args = _compiled_rollouts(sc, n, keys_of(range(n)))
    _, alone = harness.measure(compiled, *args, repeats=3, warmup=1)
    row = {"samples": n, "simulate_batch_s": whole.best_s, "compiled_call_s": alone.best_s,
           "outside_s": whole.best_s - alone.best_s}
    if profile:
        import cProfile
        import pstats

        profiler = cProfile.Profile()
        profiler.runcall(lambda: harness.measure(simulate_batch, sc, params, repeats=1, warmup=0, seeds=range(n)))
        stats = pstats.Stats(profiler).stats
        ours = [(f"{Path(f).name}:{line} {name}", cumulative) for (f, line, name), (_, _, _, cumulative, _)
                in stats.items() if "geojax" in f and "benchmarks" not in f]
        row["profile"] = dict(sorted(ours, key=lambda item: -item[1])[:15])
        for name, seconds in row["profile"].items():
            print(f"  {seconds:8.3f} s  {name}", flush=True)
    print(f"simulate_batch(seeds=range({n})): {whole.best_s:.3f} s, of which {row['outside_s']:.3f} s outside the "
          f"compiled call", flush=True)
    return row


def markdown(results: dict) -> list[str]:
    lines = ["li2022 scenarios, H_rv = H_att = 1 in the sweeps.", ""]
    if "step" in results:
        lines += ["## Uncontrolled step: geojax against the minimal kernel (orbit-years/s after compilation)", "",
                  *harness.table(["batch", "geojax", "minimal kernel", "geojax / minimal"],
                                 [[batch, f"{r['geojax_orbit_years_per_s']:.4g}",
                                   f"{r['minimal_orbit_years_per_s']:.4g}", f"{r['ratio_to_minimal']:.2f}x"]
                                  for batch, r in results["step"].items()], align="rrrr"), ""]
    if not results["sweeps"]:
        return lines + _host_lines(results)
    lines += ["## `geojax sweep` at the automatic width", "",
             *harness.table(["controller", "samples x days", "lanes per device", "sample-years/s", "after compilation",
                             "compile s", "peak memory GB", "mean ΔV m/s/yr", "ok"],
                            [[c, f"{r['samples']} x {r['days']:g}", f"{r['lanes_per_device']} ({r['lanes_source']})",
                              f"{r['sample_years_per_s']:.4g}", f"{r['run_sample_years_per_s']:.4g}",
                              f"{r['compile_s']:.1f}", f"{r['peak_memory_gb']:.2f}", f"{r['mean_dv_per_year_mps']:.3f}",
                              f"{r['status_ok_fraction']:.0%}"] for c, r in results["sweeps"].items()], align="llrrrrrrr")]
    if "engine_qffc" in results and "qffc" in results["sweeps"]:
        e, s = results["engine_qffc"], results["sweeps"]["qffc"]
        lines += ["", f"The same QFFC samples through `simulate_batch` in one call: {e['run_sample_years_per_s']:.4g} "
                  f"sample-years/s after compilation ({e['compile_s']:.1f} s), mean ΔV {e['mean_dv_per_year_mps']:.3f} "
                  f"m/s/yr; the sweep reaches {s['run_sample_years_per_s'] / e['run_sample_years_per_s']:.2f}x of it."]
    return lines + _host_lines(results)


def _host_lines(results: dict) -> list[str]:
    if "host_keys" not in results:
        return ["", "(The run stopped before the host-work part.)"]
    h = results["host_keys"]
    lines = ["", f"`simulate_batch(..., seeds=range({h['samples']}))`, one cycle: {h['simulate_batch_s']:.3f} s, "
              f"of which {h['outside_s']:.3f} s outside the compiled call ({h['compiled_call_s']:.3f} s)."]
    if "profile" in h:
        lines += ["", "Where the call's time goes (one more call under `cProfile`, cumulative seconds, geojax's "
                  "functions):", "", *harness.table(["function", "s"], [[f"`{k}`", f"{v:.3f}"]
                                                                      for k, v in h["profile"].items()], "lr")]
    return lines


if __name__ == "__main__":
    main()
