"""A sweep of clusters (a scenario with ``[[satellites]]``): every sample a whole cluster with its own draws, its
satellites in one compiled loop (``loop.cluster``), the separations' metrics per sample beside each satellite's.

A sample's metrics: the cluster's (``min_separation_km``, ``below_alert_h``, each pair's; ``alert_km``), each
satellite's as ``<metric>_<satellite>``, and for the sweep's summary columns the cluster's worst: the largest
ΔV, longitude and latitude excursion of its satellites, and the status of the first satellite that failed.
Each satellite draws from the sample's key folded with its name's id (``collocation.run``), its dispersion from
its own key's dispersion stream.
"""

from __future__ import annotations

import time
import zlib

import jax
import jax.numpy as jnp
import numpy as np

from geojax.collocation.run import cluster_rollout, coordinated
from geojax.loop.cluster import pairs
from geojax.physics.frames import earth_rotation_angle_rad
from geojax.physics.propagate import for_lanes
from geojax.runner.setup import disperse, prepare

# The summary's columns of a cluster sample: the worst of its satellites.
WORST = ("dv_per_year_mps", "max_abs_dlon_deg", "max_abs_dlat_deg")


def compiled_cluster_batch(sweep, controller: str, width: int, on_phase, devices, scenarios, groups, lanes_of,
                           dispersion_stream: int):
    """As ``sweep.batch._compiled_batch`` for a cluster's grid points (``scenarios``: each point's cluster)."""
    from geojax.parallel import per_device

    begun = time.perf_counter()
    first = scenarios[0]
    names = tuple(m.name for m in first.satellites)
    n_sat = len(names)
    if any(tuple(m.name for m in sc.satellites) != names for sc in scenarios):
        raise ValueError("satellites: every grid point must fly the same satellites")
    own = coordinated(scenarios) or sweep.custom.get(controller)  # the cluster's one program, where asked
    batches = [prepare([m for i in group for m in scenarios[i].satellites], own, states=sweep.parts)
               for group in groups]
    batch = batches[0]
    ids = jnp.asarray([zlib.crc32(name.encode()) | (1 << 31) for name in names], dtype=jnp.uint32)
    base_key = jax.random.key(sweep.seed)
    dispersion = (jnp.asarray(sweep.dispersion["mee_1sigma"]) * jnp.array([1e3, 1, 1, 1, 1, 1]),
                  jnp.asarray(sweep.dispersion["offset_ecef_1sigma_km"]) * 1e3)
    steps_per_cycle = batch.shared.env.earth_angle_rad.shape[1]
    pair_names = [f"{names[i]}_{names[j]}" for i, j in pairs(n_sat)]

    def one(point, j, shared, reference_env, angle0):
        p, alert_m, min_separation_m = point
        key = jax.random.fold_in(base_key, j)
        keys = jax.vmap(lambda i: jax.random.fold_in(key, i))(ids)
        if sweep.dispersed:
            p = jax.vmap(lambda q, k: disperse(q, jax.random.fold_in(k, dispersion_stream), *dispersion, angle0,
                                               batch.dynamics))(p, keys)
        _, _, _, satellites, cluster = cluster_rollout(
            p, keys, shared, reference_env, alert_m, min_separation_m, controller=batch.controller, step_s=batch.step_s,
            dynamics=for_lanes(batch.dynamics, batch.controller.sizing.lanes_cpu), keep_steps=False, states=batch.states,
            steps_per_cycle=steps_per_cycle)
        return named_metrics(satellites, cluster, names, pair_names, alert_m)

    def shared_of(b, group) -> tuple:
        sc = scenarios[group[0]]
        angle0 = earth_rotation_angle_rad(sc.epoch_tt_s, sc.epoch_tt_s, sc.tt_minus_ut1_s)
        return b.shared, b.reference_env if b.reference_per_sample else None, jnp.asarray(angle0)

    shared = [shared_of(b, g) for b, g in zip(batches, groups, strict=True)]
    on_phase(f"{controller}: compiling")
    # every grid point's satellites' params [n_points, n_sat, ...] and alert distance, in point order
    order = np.concatenate(groups)
    params = jax.tree_util.tree_map(
        lambda *xs: jnp.concatenate(xs).reshape((len(scenarios), n_sat) + xs[0].shape[1:])[np.argsort(order)],
        *[b.params for b in batches])
    alerts = jnp.asarray([sc.config["collocation"]["alert_km"] * 1e3 for sc in scenarios])
    points = (params, alerts, jnp.asarray([sc.config["collocation"]["min_separation_km"] * 1e3 for sc in scenarios]))
    lanes = np.zeros(width, dtype=int)
    run, _ = per_device(jax.vmap(one, in_axes=(0, 0, None, None, None)), (lanes_of(points, lanes), lanes),
                        devices=devices, shared=shared[0])
    group_of_point = np.empty(len(scenarios), dtype=int)
    for g, group in enumerate(groups):
        group_of_point[group] = g
    return (lambda p, idx, g: run(p, np.asarray(idx), shared=shared[g]), points, group_of_point,
            time.perf_counter() - begun)


def named_metrics(satellites: dict, cluster: dict, names, pair_names, alert_m) -> dict:
    """A cluster sample's metrics by name (the module's docstring)."""
    status = satellites["status"]
    failed = status != 0
    out = {key: jnp.max(satellites[key]) for key in WORST}
    out["status"] = jnp.where(jnp.any(failed), status[jnp.argmax(failed)], 0).astype(status.dtype)
    for key, values in satellites.items():
        out.update({f"{key}_{name}": values[k] for k, name in enumerate(names)})
    for key, value in cluster.items():
        if key.startswith("pair_"):
            out.update({f"{key[5:]}_{pair}": value[k] for k, pair in enumerate(pair_names)})
        else:
            out[key] = value
    out["alert_km"] = alert_m / 1e3
    return {k: jnp.asarray(v, float) if k != "status" else v for k, v in out.items()}
